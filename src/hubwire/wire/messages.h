// Message types, hello and heartbeat layouts (docs/PROTOCOL.md 2-3).
#ifndef HUBWIRE_WIRE_MESSAGES_H
#define HUBWIRE_WIRE_MESSAGES_H

#include <stdint.h>

namespace hubwire {

const uint8_t kProtocolVersion = 1;
const uint16_t kMaxDescriptor = 16384;  // the longest descriptor a hub accepts (docs/PROTOCOL.md 9)

enum MessageType : uint8_t {
  kMsgHello = '*',
  kMsgHeartbeat = 'H',
  kMsgChunk = 'J',
  kMsgRequest = 'R',
  kMsgResponse = 'r',
  kMsgControl = 'C',
  kMsgAck = 0x07,
  kMsgNak = 0x15,
  kMsgEvent = '!',
  kMsgSubscribe = 'S',
  kMsgSample = 'D',
  kMsgFragment = 'F',  // a piece of a message too long for one frame (PROTOCOL.md 12)
};

// kHelloSeqRules: the sender numbers its messages by the rules of PROTOCOL.md 4.1 (no traffic mix
// makes a new message look like a retry); a peer without it is told about (the hub warns).
enum HelloFlags : uint8_t { kHelloDevice = 1, kHelloReply = 2, kHelloF64 = 4, kHelloSeqRules = 8 };

const uint8_t kHelloSize = 16;        // a hello without the digest: what every peer accepts
const uint8_t kHelloFixed = 10;       // hello 6..15: payload limit, heartbeat, descriptor hash and length
const uint8_t kDigestSize = 16;       // the descriptor's SHA-256, first 16 bytes (hello 16..31)
const uint8_t kHelloDigestEnd = kHelloSize + kDigestSize;
const uint8_t kHeartbeatSize = 10;
const uint8_t kChunkRequestSize = 3;
const uint8_t kChunkHeader = 4;
const uint8_t kSampleHeader = 2;
const uint8_t kFragmentHeader = 5;  // carried type, offset (u16), total (u16)
const uint8_t kWindowRequest = 4;   // R asking for a window of a value: offset (u16), count (u16)
const uint8_t kWindowHeader = 8;    // its answer r: offset (u16), total (u16), the value's FNV-1a (u32)

// FNV-1a 32, the descriptor hash carried in hello.
const uint32_t kFnvOffset = 0x811C9DC5UL;
constexpr uint32_t fnv1a(uint32_t h, uint8_t b) { return (h ^ b) * 0x01000193UL; }

}  // namespace hubwire

#endif
