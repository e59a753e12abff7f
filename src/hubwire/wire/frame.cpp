#include "frame.h"

#include <string.h>

#include "bytes.h"
#include "cobs.h"
#include "crc16.h"

namespace hubwire {

void FrameReceiver::reset() {
  len_ = 0;
  left_ = 0;
  pendingZero_ = false;
  overflow_ = false;
  started_ = false;
}

bool FrameReceiver::feedSlow(uint8_t byte) {
  if (byte == 0) {  // delimiter: judge what was collected, then start afresh
    bool wasStarted = started_, overflowed = overflow_, complete = (left_ == 0);
    uint16_t len = len_;
    reset();
    if (!wasStarted) return false;  // lone delimiter: a sender flushing line noise
    if (overflowed) {
      ++counters.overflow;
      return false;
    }
    if (!complete || len < kFrameOverhead) {
      ++counters.dropped;
      return false;
    }
    uint16_t got = loadU16(buf_ + len - 2);
    if (crc16(buf_, len - 2) != got) {
      ++counters.crc;
      return false;
    }
    frameLen_ = (uint8_t)(len - kFrameOverhead);
    return true;
  }
  started_ = true;
  if (overflow_) return false;  // skip to the delimiter
  if (left_ == 0) {             // a code byte opens the next block
    if (pendingZero_) {
      if (len_ >= cap_) {
        overflow_ = true;
        return false;
      }
      buf_[len_++] = 0;
    }
    left_ = (uint8_t)(byte - 1);
    pendingZero_ = (byte != 0xFF);
    return false;
  }
  if (len_ >= cap_) {
    overflow_ = true;
    return false;
  }
  buf_[len_++] = byte;
  --left_;
  return false;
}

void FrameWriter::send(Port& out, uint8_t type, uint8_t seq, uint8_t id, uint8_t len) {
  buf_[0] = type;
  buf_[1] = seq;
  buf_[2] = id;
  uint16_t n = (uint16_t)(kFrameHeader + len);
  storeU16(buf_ + n, crc16(buf_, n));
  cobsEncodeTo(buf_, n + 2u, out);
  uint8_t delimiter = 0;
  portWrite(out, &delimiter, 1);
}

size_t encodeFrame(uint8_t type, uint8_t seq, uint8_t id, const uint8_t* payload, uint8_t len, uint8_t* out) {
  uint8_t raw[HUBWIRE_RAW_FRAME_SIZE(kProtocolMaxPayload)];
  raw[0] = type;
  raw[1] = seq;
  raw[2] = id;
  if (len) memcpy(raw + kFrameHeader, payload, len);
  uint16_t n = (uint16_t)(kFrameHeader + len);
  storeU16(raw + n, crc16(raw, n));
  size_t w = cobsEncode(raw, n + 2u, out);
  out[w++] = 0;
  return w;
}

}  // namespace hubwire
