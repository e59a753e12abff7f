// Hubwire compile-time settings. Every buffer the library owns is sized here; nothing is allocated
// at run time. Override any value with a compiler flag (PlatformIO: build_flags = -DHUBWIRE_...=N).
#ifndef HUBWIRE_CONFIG_H
#define HUBWIRE_CONFIG_H

// f64 values exist only where double is 8 bytes (not on AVR, where double is float).
#if defined(__SIZEOF_DOUBLE__) && __SIZEOF_DOUBLE__ == 8
#define HUBWIRE_HAS_F64 1
#else
#define HUBWIRE_HAS_F64 0
#endif

// The largest scalar the board carries: 8 bytes with f64, else 4. Events and action return values
// are scalars, so this is all their buffers ever need.
#define HUBWIRE_LARGEST_SCALAR (HUBWIRE_HAS_F64 ? 8 : 4)

// Largest payload the device accepts and sends (bytes). Sets the frame buffer: 5 + this.
#ifndef HUBWIRE_MAX_PAYLOAD
#define HUBWIRE_MAX_PAYLOAD 32
#endif

// Largest value a channel may declare (bytes on the wire). A value whose message does not fit one
// frame travels as fragments (docs/PROTOCOL.md 12); writes of such values are reassembled in one
// buffer sized to the largest of them, which only a sketch that declares one has.
#ifndef HUBWIRE_MAX_VALUE
#define HUBWIRE_MAX_VALUE 1024
#endif

// Events waiting for the hub's ACK, and the largest event value in bytes.
#ifndef HUBWIRE_EVENT_QUEUE
#define HUBWIRE_EVENT_QUEUE 4
#endif
#ifndef HUBWIRE_EVENT_MAX_PAYLOAD
#define HUBWIRE_EVENT_MAX_PAYLOAD HUBWIRE_LARGEST_SCALAR
#endif

// Channels the hub may subscribe to at the same time.
#ifndef HUBWIRE_MAX_STREAMS
#define HUBWIRE_MAX_STREAMS 4
#endif

// Largest return value of a callable action (bytes), kept to answer a retried call without
// calling the function twice.
#ifndef HUBWIRE_MAX_RETURN
#define HUBWIRE_MAX_RETURN HUBWIRE_LARGEST_SCALAR
#endif

// Highest channel id, 1..254 (channels are numbered 1..N in declaration order). The compiler builds
// the descriptor, its hash and digest and the channel tables: a sketch of 32 float channels with a
// range, a unit and 60-character descriptions (4.3 KB of JSON) takes avr-gcc 5.4 147 MiB and
// 0.5 s of CPU for the Uno, g++ 12 (the emulator; boards of a modern GCC alike) 140 MiB and 0.8 s
// (make test-compile-cost checks both fit 256 MiB); 80 such channels about 300 and 270 MiB, 254
// plain ones 320 and 410 MiB. A descriptor over the 16 KiB a hub accepts is refused before it is
// built, in well under a second (bench/DESCRIPTOR-COMPILE.md).
#ifndef HUBWIRE_MAX_CHANNELS
#define HUBWIRE_MAX_CHANNELS 32
#endif

// Timing, in milliseconds.
#ifndef HUBWIRE_HEARTBEAT_MS
#define HUBWIRE_HEARTBEAT_MS 250
#endif
#ifndef HUBWIRE_EVENT_RETRY_MS
#define HUBWIRE_EVENT_RETRY_MS 100
#endif
#ifndef HUBWIRE_ANNOUNCE_MS
#define HUBWIRE_ANNOUNCE_MS 1000
#endif
#ifndef HUBWIRE_MIN_STREAM_INTERVAL_MS
#define HUBWIRE_MIN_STREAM_INTERVAL_MS 10
#endif
// The link is lost after this many of the hub's heartbeat intervals without a valid frame.
#ifndef HUBWIRE_LOST_AFTER_BEATS
#define HUBWIRE_LOST_AFTER_BEATS 4
#endif

// Talking to the hub's own channels (remote(), remoteAction(), remoteEvent()): only a sketch that
// declares one pays for any of this (session/hub_link.h).
// The most hub channels a sketch declares (the bind report carries one status byte each).
#ifndef HUBWIRE_MAX_HUB_CHANNELS
#define HUBWIRE_MAX_HUB_CHANNELS 8
#endif
// Requests, writes and calls waiting for the hub, and the largest value one carries (bytes): a
// written value or an action's argument is copied when queued.
#ifndef HUBWIRE_HUB_QUEUE
#define HUBWIRE_HUB_QUEUE 4
#endif
#ifndef HUBWIRE_HUB_MAX_VALUE
#define HUBWIRE_HUB_MAX_VALUE 8
#endif
// A request unanswered for this long is sent again (same seq), up to this many tries in all.
#ifndef HUBWIRE_HUB_RETRY_MS
#define HUBWIRE_HUB_RETRY_MS 100
#endif
#ifndef HUBWIRE_HUB_TRIES
#define HUBWIRE_HUB_TRIES 5
#endif

// Keeps a small function called from many places out of line, where GCC's inlining would repeat it.
#if defined(__GNUC__)
#define HUBWIRE_NOINLINE __attribute__((noinline))
#define HUBWIRE_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define HUBWIRE_NOINLINE
#define HUBWIRE_ALWAYS_INLINE inline
#endif

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "Hubwire copies values as little-endian memory; big-endian targets are not supported"
#endif

namespace hubwire {
static_assert(HUBWIRE_MAX_PAYLOAD >= 16 && HUBWIRE_MAX_PAYLOAD <= 255,
              "HUBWIRE_MAX_PAYLOAD must be 16..255 (hello needs 16 bytes)");
static_assert(HUBWIRE_MAX_VALUE >= 1 && HUBWIRE_MAX_VALUE <= 65535L, "HUBWIRE_MAX_VALUE must be 1..65535");
static_assert(HUBWIRE_EVENT_QUEUE >= 1 && HUBWIRE_EVENT_QUEUE <= 64, "HUBWIRE_EVENT_QUEUE must be 1..64");
static_assert(HUBWIRE_EVENT_MAX_PAYLOAD >= 1 && HUBWIRE_EVENT_MAX_PAYLOAD <= HUBWIRE_MAX_PAYLOAD,
              "HUBWIRE_EVENT_MAX_PAYLOAD must be 1..HUBWIRE_MAX_PAYLOAD");
static_assert(HUBWIRE_MAX_STREAMS >= 0 && HUBWIRE_MAX_STREAMS <= 32, "HUBWIRE_MAX_STREAMS must be 0..32");
static_assert(HUBWIRE_MAX_RETURN >= 1 && HUBWIRE_MAX_RETURN <= HUBWIRE_MAX_PAYLOAD,
              "HUBWIRE_MAX_RETURN must be 1..HUBWIRE_MAX_PAYLOAD");
// Channel ids are one byte: the first channel too many (reported by its id) must still fit.
static_assert(HUBWIRE_MAX_CHANNELS >= 1 && HUBWIRE_MAX_CHANNELS <= 254, "HUBWIRE_MAX_CHANNELS must be 1..254");
static_assert(HUBWIRE_HEARTBEAT_MS >= 10 && HUBWIRE_HEARTBEAT_MS <= 60000, "HUBWIRE_HEARTBEAT_MS must be 10..60000");
static_assert(HUBWIRE_LOST_AFTER_BEATS >= 2, "HUBWIRE_LOST_AFTER_BEATS must be at least 2");
// The device keeps 16-bit millisecond times: every interval must stay below 65.5 s.
static_assert((long)HUBWIRE_HEARTBEAT_MS * HUBWIRE_LOST_AFTER_BEATS <= 65535L,
              "HUBWIRE_HEARTBEAT_MS x HUBWIRE_LOST_AFTER_BEATS must be at most 65535 ms");
static_assert(HUBWIRE_ANNOUNCE_MS >= 10 && HUBWIRE_ANNOUNCE_MS <= 60000, "HUBWIRE_ANNOUNCE_MS must be 10..60000");
static_assert(HUBWIRE_MIN_STREAM_INTERVAL_MS >= 1 && HUBWIRE_MIN_STREAM_INTERVAL_MS <= 60000,
              "HUBWIRE_MIN_STREAM_INTERVAL_MS must be 1..60000 (the longest interval granted)");
static_assert(HUBWIRE_EVENT_RETRY_MS >= 10 && HUBWIRE_EVENT_RETRY_MS <= 60000, "HUBWIRE_EVENT_RETRY_MS must be 10..60000");
static_assert(HUBWIRE_MAX_HUB_CHANNELS >= 1 && HUBWIRE_MAX_HUB_CHANNELS <= 254 &&
                  HUBWIRE_MAX_HUB_CHANNELS + 1 <= HUBWIRE_MAX_PAYLOAD,
              "HUBWIRE_MAX_HUB_CHANNELS must be 1..254 and below HUBWIRE_MAX_PAYLOAD (the bind report)");
static_assert(HUBWIRE_HUB_QUEUE >= 1 && HUBWIRE_HUB_QUEUE <= 32, "HUBWIRE_HUB_QUEUE must be 1..32");
static_assert(HUBWIRE_HUB_MAX_VALUE >= 3 && HUBWIRE_HUB_MAX_VALUE <= HUBWIRE_MAX_PAYLOAD,
              "HUBWIRE_HUB_MAX_VALUE must be 3..HUBWIRE_MAX_PAYLOAD");
static_assert(HUBWIRE_HUB_RETRY_MS >= 10 && HUBWIRE_HUB_TRIES >= 1 && HUBWIRE_HUB_TRIES <= 255 &&
                  (long)HUBWIRE_HUB_RETRY_MS * HUBWIRE_HUB_TRIES <= 65535L,
              "HUBWIRE_HUB_RETRY_MS x HUBWIRE_HUB_TRIES must be at most 65535 ms (RETRY_MS >= 10, TRIES 1..255)");
}  // namespace hubwire

#endif
