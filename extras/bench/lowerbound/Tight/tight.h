// Tight: a size-first device side of the Hubwire protocol (docs/PROTOCOL.md), for AVR.
// The descriptor JSON is a flash constant prepared at compile time; channels are a flash table.
#ifndef TIGHT_H
#define TIGHT_H

#include <Arduino.h>

#define TW_MAX_PAYLOAD 32     // HUBWIRE_MAX_PAYLOAD
#define TW_EVENT_QUEUE 4      // HUBWIRE_EVENT_QUEUE
#define TW_EVENT_MAX 4        // HUBWIRE_EVENT_MAX_PAYLOAD on AVR
#define TW_MAX_STREAMS 4      // HUBWIRE_MAX_STREAMS
#define TW_HEARTBEAT_MS 250
#define TW_EVENT_RETRY_MS 100
#define TW_ANNOUNCE_MS 1000
#define TW_MIN_STREAM_MS 10
#define TW_LOST_AFTER 4
// Compile-time pruning: a generator knows whether any channel is streamable or has a failsafe.
#ifndef TW_HAS_STREAMS
#define TW_HAS_STREAMS 1
#endif
#ifndef TW_HAS_FAILSAFE
#define TW_HAS_FAILSAFE 1
#endif

enum : uint8_t { TW_R = 1, TW_W = 2, TW_C = 4, TW_E = 8, TW_S = 16 };
enum : uint8_t { TW_BOOL = 0x80 };  // in TwChannel::size: value must be 0 or 1

// One channel, in flash. Generated at compile time from the declarations.
struct TwChannel {
  uint8_t* data;                      // the variable (readable / writable), or null
  bool (*call)(const uint8_t* v);     // control function or change callback; false = REJECTED
  bool (*inRange)(const uint8_t* v);  // range check, or null
  const uint8_t* failsafe;            // failsafe bytes in flash, or null
  uint8_t access;
  uint8_t size;                       // wire size | TW_BOOL
};

// Provided by the sketch (compile-time tables).
extern const TwChannel twChannels[] PROGMEM;
extern const uint8_t twChannelCount;
extern const char twDescriptor[] PROGMEM;
extern const uint16_t twDescLength;
// Hello bytes 6..15, all compile-time constants: max payload, heartbeat, descriptor hash, length.
extern const uint8_t twHelloTail[10] PROGMEM;
#define TW_U16(v) (uint8_t)(v), (uint8_t)((v) >> 8)
#define TW_U32(v) TW_U16(v), TW_U16((v) >> 16)

void twBegin();
void twUpdate();
bool twEmit(uint8_t id, const void* v, uint8_t n);

// FNV-1a 32 at compile time (C++11 constexpr: one return statement).
constexpr uint32_t twFnv(const char* s, uint16_t n, uint32_t h = 0x811C9DC5UL) {
  return n == 0 ? h : twFnv(s + 1, n - 1, (uint32_t)((h ^ (uint8_t)*s) * 0x01000193ULL));
}

#endif
