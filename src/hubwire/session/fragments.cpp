#include "fragments.h"

#include <string.h>

#include "../wire/bytes.h"
#include "../wire/messages.h"
#include "session.h"

namespace hubwire {

namespace {

// Messages a device answers: one too large for it gets NAK BAD_LENGTH instead of silence.
bool answered(uint8_t type) {
  return type == kMsgRequest || type == kMsgControl || type == kMsgChunk || type == kMsgSubscribe;
}

}  // namespace

void fragmentReceived(Session& s, const Frame& f) {
  Reassembly* r = HubwireLarge<true, void>::state;
  uint16_t capacity = r ? HubwireLarge<true, void>::capacity : 0;
  if (f.len <= kFragmentHeader) {
    ++s.rx_.counters.dropped;
    return;
  }
  const uint8_t* p = f.payload;
  uint8_t type = p[0];
  uint16_t offset = loadU16(p + 1), total = loadU16(p + 3), n = (uint16_t)(f.len - kFragmentHeader);
  bool same = r && r->total && type == r->type && f.seq == r->seq && f.id == r->id && total == r->total;
  if (same && r->next == total) {
    // Complete and handled already. While the session still remembers that control, this is its
    // retry (its answer was lost): the last fragment has it answered again from that memory, not
    // applied again, where the retry would otherwise have to come whole once more. Else it is
    // another message: the old one is forgotten.
    if (s.lastTxnControl_ && f.seq == s.lastTxnSeq_ && f.id == s.lastTxnId_) {
      if (total - offset == n) s.handle(Frame{type, f.seq, f.id, 0xFF, reassemblyData(r)});
      return;
    }
    r->total = 0;
    same = false;
  }
  if (same) {
    // The message in progress, or a retry of it: a retry carries the same bytes (4.1, rule 1), so
    // what is here stays, a fragment it has is skipped and one past a gap dropped. Each try then
    // adds to the last, and a long value needs tries in proportion to its length, not to the
    // chance of a whole try getting through.
    if (offset != r->next || total - offset < n) {
      if (offset > r->next) ++s.rx_.counters.dropped;
      return;
    }
  } else if (offset == 0) {  // a new message: whatever was in progress is abandoned
    if (r) r->total = 0;
    if (total > capacity && total >= n) {
      if (answered(type)) return s.sendNak(kErrBadLength);  // seq and id are the carried message's
      ++s.rx_.counters.overflow;
      return;
    }
    if (total < n || type == kMsgFragment) {
      ++s.rx_.counters.dropped;
      return;
    }
    r->type = type;
    r->seq = f.seq;
    r->id = f.id;
    r->total = total;
    r->next = 0;
  } else {
    // Another message's fragment past its start (the start was lost): the one in progress is
    // abandoned, never completed with another message's bytes.
    if (r) r->total = 0;
    ++s.rx_.counters.dropped;
    return;
  }
  uint8_t* data = reassemblyData(r);
  memcpy(data + offset, p + kFragmentHeader, n);
  r->next = (uint16_t)(offset + n);
  if (r->next != total) return;  // complete: kept so, for a retry (above), until another message
  if (!answered(type)) {  // the hub sends the device nothing else this long (hub values fit a frame)
    r->total = 0;
    ++s.rx_.counters.dropped;
    return;
  }
  // Handled as if it had come in one frame. len 0xFF is what no R, J or S carries (they answer
  // BAD_LENGTH, as for a long one); a control reads the whole length (wholeLength(): r->next).
  s.handle(Frame{type, f.seq, f.id, 0xFF, data});
}

bool sendLarge(Session& s, uint8_t type, uint8_t seq, uint8_t id, const ChannelInfo& ch, const uint8_t* prefix,
               uint8_t prefixLen, bool room) {
  if (type == kMsgRequest) {
    // The answer to a window request (PROTOCOL.md 12.8), whose payload is prefix: one frame,
    // [offset, total, FNV-1a of the whole wire form, bytes offset..]. The hash is taken through
    // wireRange in pieces the size of the frame's free room, which the window's bytes then fill: no
    // copy of the value, and the sketch's loop() does not run in between: one snapshot.
    uint16_t offset = loadU16(prefix), count = loadU16(prefix + 2);
    uint16_t total = ch.type.wireLength(ch.data);
    if (offset > total) return s.sendNak(kErrBadOffset), true;
    uint8_t* out = s.tx().payload();
    uint8_t room = (uint8_t)(s.maxOut() - kWindowHeader);  // maxOut() >= 16
    uint8_t* at = out + kWindowHeader;
    uint32_t h = kFnvOffset;
    for (uint16_t from = 0; from < total;) {
      uint8_t k = total - from < room ? (uint8_t)(total - from) : room;
      ch.type.wireRange(ch.data, from, at, k);
      for (uint8_t i = 0; i < k; ++i) h = fnv1a(h, at[i]);
      from = (uint16_t)(from + k);
    }
    uint16_t n = total - offset;
    if (n > room) n = room;
    if (n > count) n = count;
    ch.type.wireRange(ch.data, offset, at, n);
    storeU16(out, offset);
    storeU16(out + 2, total);
    storeU32(out + 4, h);
    s.send(kMsgResponse, seq, id, (uint8_t)(kWindowHeader + n));
    return true;
  }
  uint16_t total = (uint16_t)(prefixLen + ch.type.wireLength(ch.data));
  uint8_t* out = s.tx().payload();
  uint8_t max = s.maxOut();
  if (total <= max) {  // a list that is not full may fit after all
    if (room && portWritable(s.port_) < FrameWriter::wireSize(total)) return false;
    if (prefixLen) memcpy(out, prefix, prefixLen);  // a read has none (prefix nullptr)
    ch.type.toWire(ch.data, out + prefixLen);
    s.send(type, seq, id, (uint8_t)total);
    return true;
  }
  uint8_t per = (uint8_t)(max - kFragmentHeader);  // max >= 16
  if (room && portWritable(s.port_) < FrameWriter::wireSize(max)) return false;
  // Back to back, offset 0 first; the sketch's loop() does not run in between: one snapshot.
  for (uint16_t offset = 0; offset < total; offset = (uint16_t)(offset + per)) {
    uint16_t n = total - offset < per ? (uint16_t)(total - offset) : per;
    out[0] = type;
    storeU16(out + 1, offset);
    storeU16(out + 3, total);
    uint8_t* at = out + kFragmentHeader;
    uint16_t from = offset, left = n;
    while (from < prefixLen && left) {
      *at++ = prefix[from++];
      --left;
    }
    ch.type.wireRange(ch.data, (uint16_t)(from - prefixLen), at, left);
    s.send(kMsgFragment, seq, id, (uint8_t)(kFragmentHeader + n));
  }
  return true;
}

}  // namespace hubwire
