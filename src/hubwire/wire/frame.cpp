#include "frame.h"

#include <string.h>

#include "bytes.h"
#include "cobs.h"
#include "crc16.h"

namespace hubwire {

template <typename Index>
void FrameDecoderOf<Index>::reset() {
  at_ = 0;
  fitEnd_ = 0;
  beyond_ = 0;
  pendingZero_ = false;
  started_ = false;
}

template <typename Index>
bool FrameDecoderOf<Index>::feedSlow(uint8_t byte, uint8_t* buf, Index cap) {
  if (byte == 0) {  // delimiter: judge what was collected, then start afresh
    bool wasStarted = started_, overflowed = beyond_ == kOverflowed, complete = (at_ == fitEnd_ && beyond_ == 0);
    Index len = at_;
    reset();
    if (!wasStarted) return false;  // lone delimiter: a sender flushing line noise
    uint16_t* bad;  // the counter of the reason it is dropped: one increment for all of them
    if (overflowed) {
      bad = &counters.overflow;
    } else if (!complete || len < kFrameOverhead) {
      bad = &counters.dropped;
    } else if (crc16(buf, len - 2) != loadU16(buf + len - 2)) {
      bad = &counters.crc;
    } else {
      frameLen_ = (uint8_t)(len - kFrameOverhead);
      return true;
    }
    ++*bad;
    return false;
  }
  started_ = true;
  if (beyond_ != 0) {  // a data byte past the end of the buffer, or one after it: skip to the delimiter
    beyond_ = kOverflowed;
    return false;
  }
  // A code byte opens the next block: the zero the last one implied, then up to code - 1 bytes,
  // those that fit up to fitEnd_, the rest counted in beyond_.
  if (pendingZero_) {
    if (at_ >= cap) {
      beyond_ = kOverflowed;
      return false;
    }
    buf[at_++] = 0;
  }
  uint8_t n = (uint8_t)(byte - 1);
  Index room = (Index)(cap - at_);
  uint8_t fit = room < n ? (uint8_t)room : n;
  fitEnd_ = (Index)(at_ + fit);
  beyond_ = (uint8_t)(n - fit);
  pendingZero_ = (byte != 0xFF);
  return false;
}

// The session's (an index of one byte) and FrameReceiver's.
template class FrameDecoderOf<uint8_t>;
template class FrameDecoderOf<uint16_t>;

template <bool kLongBlocks>
void sendFrame(Port& out, uint8_t* buf, uint8_t type, uint8_t seq, uint8_t id, uint8_t len) {
  uint8_t* raw = buf + 1;
  raw[0] = type;
  raw[1] = seq;
  raw[2] = id;
  uint16_t n = (uint16_t)(kFrameHeader + len);
  storeU16(raw + n, crc16(raw, n));
  // COBS in place: code points at the slot of the open block's code byte (buf[0], then each zero
  // as it is reached), run counts from it to p, from is the first byte not yet written.
  uint8_t* code = buf;
  uint8_t* from = buf;
  uint8_t* end = raw + n + 2;
  uint8_t run = 1;
  for (uint8_t* p = raw; p != end; ++p, ++run) {
    if (kLongBlocks && run == 0xFF) {  // 254 data bytes: a full block, no implied zero; the next
      *code = 0xFF;                     // block's code goes where its last byte was, once written
      portWrite(out, from, (size_t)(p - from));
      from = code = p - 1;
      run = 1;
    }
    if (*p == 0) {
      *code = run;
      code = p;
      run = 0;
    }
  }
  *code = run;
  *end = 0;  // the delimiter
  portWrite(out, from, (size_t)(end + 1 - from));
}

template void sendFrame<true>(Port&, uint8_t*, uint8_t, uint8_t, uint8_t, uint8_t);
template void sendFrame<false>(Port&, uint8_t*, uint8_t, uint8_t, uint8_t, uint8_t);

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
