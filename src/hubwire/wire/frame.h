// Frames: type, seq, id, payload and a CRC-16, COBS-encoded and ended by 0x00 (docs/PROTOCOL.md 1).
#ifndef HUBWIRE_WIRE_FRAME_H
#define HUBWIRE_WIRE_FRAME_H

#include <stddef.h>
#include <stdint.h>

#include "../config.h"
#include "../port.h"

namespace hubwire {

const uint8_t kFrameHeader = 3;    // type, seq, id
const uint8_t kFrameOverhead = 5;  // header + CRC
const uint16_t kProtocolMaxPayload = 255;

// Raw frame bytes needed to hold a payload of n bytes.
#define HUBWIRE_RAW_FRAME_SIZE(n) ((n) + 5)
// A FrameWriter's buffer for payloads of up to n bytes: the raw frame, the slot of the first COBS
// code byte before it and the delimiter after it (the frame is encoded where it was built).
#define HUBWIRE_SEND_FRAME_SIZE(n) ((n) + 7)

// A decoded frame. payload points into the receiver's buffer and stays valid until the next feed().
struct Frame {
  uint8_t type;
  uint8_t seq;
  uint8_t id;
  uint8_t len;
  const uint8_t* payload;
};

// Frames the receiver dropped, by reason (reported in heartbeats; they wrap).
struct LinkCounters {
  uint16_t crc;       // CRC mismatch
  uint16_t overflow;  // longer than the buffer
  uint16_t dropped;   // bad COBS, too short, or rejected by the layer above
};

// Decodes the incoming byte stream one byte at a time into a fixed buffer, COBS on the fly. The
// buffer is not kept here but passed to each call, and positions in it are indices: the session
// shares one buffer with its writer (session.h), so it stores no pointers for this and its
// constructor sets none. Index counts the buffer's bytes: uint8_t for a buffer of up to 255 bytes
// (the session's, unless HUBWIRE_MAX_PAYLOAD is above 250), uint16_t for any. FrameReceiver below
// is the same with a buffer of its own.
template <typename Index>
class FrameDecoderOf {
 public:
  // Value-initialised (as a member of a value-initialised whole) it is all zero: ready, nothing
  // received.
  FrameDecoderOf() = default;

  // Takes one byte into buf, which holds cap raw bytes (HUBWIRE_RAW_FRAME_SIZE(largest accepted
  // payload)), the same buf and cap at every call; true when it completed a valid frame, which
  // frame(buf) then describes.
  // Most bytes are data inside a COBS block that fit the buffer: that case is a compare and a
  // store, always inline (the receive loop runs it per byte); the rest is feedSlow().
  HUBWIRE_ALWAYS_INLINE bool feed(uint8_t byte, uint8_t* buf, Index cap) {
    Index at = at_;
    if (at != fitEnd_ && byte != 0) {
      at_ = (Index)(at + 1);  // before the store through buf, which could alias it
      buf[at] = byte;
      return false;
    }
    return feedSlow(byte, buf, cap);
  }
  // The frame, by value: its header is copied out, so an answer built in the same buffer cannot
  // change it. The payload stays in the buffer.
  Frame frame(const uint8_t* buf) const { return Frame{buf[0], buf[1], buf[2], frameLen_, buf + kFrameHeader}; }
  // Forget any partial frame (the next byte starts a new one). Two callers in the session: one copy.
  HUBWIRE_NOINLINE void reset();
  // No frame is partly received: the buffer holds nothing that is still needed.
  bool idle() const { return !started_; }

  LinkCounters counters;

 private:
  bool feedSlow(uint8_t byte, uint8_t* buf, Index cap);
  static const uint8_t kOverflowed = 0xFF;

  Index at_;             // where the next decoded byte goes (bytes decoded so far)
  Index fitEnd_;         // where the bytes of the current COBS block that fit the buffer end
  uint8_t beyond_;       // bytes of the block still to come that do not fit (the frame overflows
                         // if one arrives); kOverflowed once one did (a block holds at most 254)
  bool pendingZero_;     // the current block ends with an implied zero (code < 0xFF)
  bool started_;         // any byte since the last delimiter
  uint8_t frameLen_;     // payload length of the last completed frame
};

// A FrameDecoder with a buffer of its own (tests, tools, a hub written in C++).
class FrameReceiver : public FrameDecoderOf<uint16_t> {
 public:
  // buffer holds capacity raw bytes: HUBWIRE_RAW_FRAME_SIZE(largest accepted payload).
  FrameReceiver(uint8_t* buffer, uint16_t capacity) : FrameDecoderOf<uint16_t>(), buf_(buffer), cap_(capacity) {}

  // Takes one byte; true when it completed a valid frame, which frame() then describes.
  bool feed(uint8_t byte) { return FrameDecoderOf<uint16_t>::feed(byte, buf_, cap_); }
  Frame frame() const { return FrameDecoderOf<uint16_t>::frame(buf_); }

 private:
  uint8_t* buf_;
  uint16_t cap_;
};

// Header, CRC and COBS in place in buf (see FrameWriter), then one write of the frame (two past
// 254 bytes). kLongBlocks: frames of 255 raw bytes and more need a COBS block without an implied
// zero (code 0xFF); a writer whose payloads stay below 250 bytes leaves that case out.
template <bool kLongBlocks>
void sendFrame(Port& out, uint8_t* buf, uint8_t type, uint8_t seq, uint8_t id, uint8_t len);

// Builds frames in a fixed buffer and writes them COBS-encoded to a stream. The encoding is done
// in the buffer itself (each zero becomes the code byte of the block it ends), so a frame goes out
// in one write (two past 254 bytes) without a copy; send() leaves the buffer's contents undefined.
// kMaxPayload: the longest payload it sends (the session's is HUBWIRE_MAX_PAYLOAD).
template <uint16_t kMaxPayload = kProtocolMaxPayload>
class BasicFrameWriter {
 public:
  // buffer: HUBWIRE_SEND_FRAME_SIZE(kMaxPayload) bytes. A receiver may share it from buffer + 1
  // on: its frame's payload is then where this writer's goes.
  explicit BasicFrameWriter(uint8_t* buffer) : buf_(buffer) {}
  // Where the payload goes.
  uint8_t* payload() { return buf_ + 1 + kFrameHeader; }
  // Wire bytes a frame with this payload length takes at most (COBS code bytes and delimiter).
  static size_t wireSize(size_t len) { return len + kFrameOverhead + (len + kFrameOverhead) / 254 + 2; }
  // The same for a payload length that fits a byte, without the division (a library call on AVR).
  static uint16_t wireSize8(uint8_t len) { return (uint16_t)(len + kFrameOverhead + 2 + (len + kFrameOverhead >= 254)); }
  // Adds header and CRC to the len payload bytes already in payload(), and sends the frame.
  void send(Port& out, uint8_t type, uint8_t seq, uint8_t id, uint8_t len) {
    sendFrame<(kMaxPayload + kFrameOverhead >= 0xFE)>(out, buf_, type, seq, id, len);
  }

 private:
  uint8_t* buf_;
};
typedef BasicFrameWriter<> FrameWriter;

// Encodes a whole frame into out (room for FrameWriter::wireSize(len)); returns bytes written,
// delimiter included. For tests and tools; the device sends with FrameWriter.
size_t encodeFrame(uint8_t type, uint8_t seq, uint8_t id, const uint8_t* payload, uint8_t len, uint8_t* out);

}  // namespace hubwire

#endif
