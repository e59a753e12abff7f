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

// Decodes the incoming byte stream one byte at a time into a fixed buffer, COBS on the fly.
class FrameReceiver {
 public:
  // buffer holds capacity raw bytes: HUBWIRE_RAW_FRAME_SIZE(largest accepted payload).
  FrameReceiver(uint8_t* buffer, uint16_t capacity) : counters(), buf_(buffer), end_(buffer + capacity) { reset(); }
  // A receiver without a buffer yet: value-initialised (FrameReceiver r{} or as a member of a
  // value-initialised whole) it is all zero, and attach() then sets only its pointers.
  FrameReceiver() = default;

  // Gives a zeroed receiver its buffer.
  void attach(uint8_t* buffer, uint16_t capacity) {
    buf_ = at_ = buffer;
    end_ = buffer + capacity;
  }

  // Takes one byte; true when it completed a valid frame, which frame() then describes.
  // Most bytes are data inside a COBS block that fit the buffer: that case is a store and a count,
  // always inline (the receive loop runs it per byte); the rest is feedSlow().
  HUBWIRE_ALWAYS_INLINE bool feed(uint8_t byte) {
    if (byte != 0 && left_ != 0) {
      *at_++ = byte;
      --left_;
      return false;
    }
    return feedSlow(byte);
  }
  // The frame, by value: its header is copied out, so an answer built in the same buffer cannot
  // change it. The payload stays in the buffer.
  Frame frame() const { return Frame{buf_[0], buf_[1], buf_[2], frameLen_, buf_ + kFrameHeader}; }
  // Forget any partial frame (the next byte starts a new one).
  void reset();
  // No frame is partly received: the buffer holds nothing that is still needed.
  bool idle() const { return !started_; }

  LinkCounters counters;

 private:
  HUBWIRE_NOINLINE bool feedSlow(uint8_t byte);
  HUBWIRE_ALWAYS_INLINE bool judge(uint8_t byte);  // feedSlow()'s body
  static const uint8_t kOverflowed = 0xFF;

  uint8_t* buf_;
  uint8_t* end_;         // just past the buffer
  uint8_t* at_;          // where the next decoded byte goes
  uint8_t left_;         // bytes of the current COBS block still to come that fit the buffer
  uint8_t beyond_;       // ... and that do not (the frame overflows if one arrives); kOverflowed
                         // once one did (a block holds at most 254)
  bool pendingZero_;     // the current block ends with an implied zero (code < 0xFF)
  bool started_;         // any byte since the last delimiter
  uint8_t frameLen_;     // payload length of the last completed frame
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
