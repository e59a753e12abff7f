// The session's channel work: finding a channel's record, answering reads, applying controls
// and calls, subscriptions and their samples, and the failsafes at a link loss (docs/PROTOCOL.md
// 4-7). The rest of the session, the link itself, is session.cpp.
#include "../channels/hub_table.h"
#include "../features.h"
#include "../wire/bytes.h"
#include "hooks.h"
#include "session.h"

namespace hubwire {

// A list's elements (its count first) against the channel's range.
static ErrorCode listInRange(const ChannelLimits& lim, TypeCode code, const uint8_t* wire) {
  uint8_t size = scalarSize(elementOf(code));
  for (uint8_t i = 0; i < wire[0]; ++i)
    if (!lim.inRange(wire + 1 + i * size, &lim.min, &lim.max)) return kErrOutOfRange;
  return kOk;
}

bool Session::find(uint8_t id, ChannelInfo& ch) {
  if (id == 0 || id > table(&ChannelTable::count)) return false;
  flashCopy(&ch, &table(&ChannelTable::channels)[id - 1], sizeof(ch));
  return true;
}

// Variables with a failsafe value take it (every element of an array), then their onChange runs,
// once per link loss whether or not the value changed, as after a hub's write; a control with one
// is called with it. Either way: as if the hub had sent it.
void Session::applyFailsafes() {
  if (!uses(kUsesFailsafes)) return;
  const uint8_t count = table(&ChannelTable::count);
  for (uint8_t id = 1; id <= count; ++id) {
    ChannelInfo ch;
    if (!find(id, ch) || !(ch.flags & kHasFailsafe)) continue;
    Scalar fs = flashRead(&ch.limits->failsafe);
    if (!uses(kUsesControlFailsafes) || ch.data) {
      uint8_t n = ch.type.count ? ch.type.count : 1;
      uint8_t size = scalarSize(ch.type.code);
      uint8_t* d = (uint8_t*)ch.data;
      for (uint8_t i = 0; i < n; ++i, d += size) memcpy(d, &fs, size);
      if (ch.call) functionAt<void (*)()>(ch.call)();
    } else {
      Scalar ignored;
      ch.thunk(ch.call, (const uint8_t*)&fs, (uint8_t*)&ignored);
    }
  }
}

void Session::onRequest(const Frame& f) {
  ChannelInfo ch;
  if (!find(f.id, ch)) {
    // Id 0 is the link itself: reading it asks for the board id (at most 16 bytes, which every
    // hub accepts), where the board has one.
    uint8_t n = f.id == 0 && f.len == 0 ? portBoardId(port_, tx().payload()) : 0;
    if (n) return reply(kMsgResponse, n);
    return sendNak(kErrUnknownChannel);
  }
  if (!uses(kUsesReads) || !(ch.access & kReadable)) return sendNak(kErrNotReadable);
  // A window of the value (PROTOCOL.md 12.8): only a sketch with a large value has the hook.
  if (HubwireLarge<true, void>::send && f.len == kWindowRequest)
    return (void)HubwireLarge<true, void>::send(*this, kMsgRequest, f.seq, f.id, ch, f.payload, kWindowRequest, false);
  // Not sent at all when the hub could not take it (its hello said how much it accepts), unless
  // it may go as fragments (fragments.cpp).
  if (f.len != 0 || (uses(kUsesWide) && !HubwireLarge<true, void>::send && ch.type.wireSize() > maxOut()))
    return sendNak(kErrBadLength);
  if (HubwireLarge<true, void>::send)
    return (void)HubwireLarge<true, void>::send(*this, kMsgResponse, f.seq, f.id, ch, nullptr, 0, false);
  reply(kMsgResponse, (uint8_t)ch.type.toWire(ch.data, tx().payload()));
}

void Session::onControl(const Frame& f) {
  uint8_t code = kOk;
  uint8_t type = kMsgAck, len = 0;
  ChannelInfo ch;
  if (!find(f.id, ch)) {
    code = kErrUnknownChannel;
  } else if (!(ch.access & (kWritable | kCallable))) {
    code = kErrNotWritable;
  } else {
    const ValueType& t = ch.type;
    code = t.check(f.payload, wholeLength(f));  // f.len, or a reassembled control's (fragments.h)
    if (code == kOk && uses(kUsesRanges) && (ch.flags & kHasRange)) {
      ChannelLimits lim;
      flashCopy(&lim, ch.limits, sizeof(lim));
      uint8_t n = t.count ? t.count : 1, size = scalarSize(t.code);
      const uint8_t* v = f.payload;
      for (uint8_t i = 0; i < n; ++i, v += size)
        if (!lim.inRange(v, &lim.min, &lim.max)) code = kErrOutOfRange;
      // A List: the loop above read its count byte as an element (size 0); the verdict on its
      // elements is this one. After the loop, where it leaves the other sketches' code alone.
      if (uses(kUsesLists) && isListCode(t.code)) code = listInRange(lim, t.code, f.payload);
    }
    if (code == kOk) {
      if (uses(kUsesCalls) && ch.thunk) {
        uint8_t* ret = tx().payload();
        if (!ch.thunk(ch.call, f.payload, ret)) {
          code = kErrRejected;
        } else if (uses(kUsesReturns) && ch.ret != kVoid) {
          type = kMsgResponse;
          len = scalarSize(ch.ret);
          if (uses(kUsesLists) && isListCode(ch.ret)) len = (uint8_t)(1 + ret[0] * scalarSize(elementOf(ch.ret)));
        }
      } else if (uses(kUsesWrites)) {
        t.fromWire(f.payload, wholeLength(f), ch.data);
        if (ch.call) functionAt<void (*)()>(ch.call)();
      }
    }
  }
  if (code != kOk) {
    type = kMsgNak;
    len = 1;
    tx().payload()[0] = code;
  }
  if (hubHook(*this, true)) return;  // the bind report (C id 0); the hub link notes every control
  replyType_ = type;
  replyLen_ = len;
  // Without returns the answer is an ACK or a NAK: its code is all to keep (read back after an ACK).
  if (uses(kUsesReturns)) memcpy(replyData_, tx().payload(), len);
  else replyData_[0] = code;
  reply(type, len);
}

void Session::onSubscribe(const Frame& f) {
  ChannelInfo ch;
  if (!find(f.id, ch)) return sendNak(kErrUnknownChannel);
  if (!uses(kUsesStreams) || !(ch.access & kStreamable)) return sendNak(kErrNotStreamable);
  if (f.len != 2 || (uses(kUsesWide) && !HubwireLarge<true, void>::send && ch.type.wireSize() + kSampleHeader > maxOut()))
    return sendNak(kErrBadLength);
  uint16_t interval = loadU16(f.payload);
#if HUBWIRE_MAX_STREAMS > 0
  // Timed by update()'s clock read, as the frame is: the first sample's time since is from then.
  if (!streams_.subscribe(f.id, interval, lastRx_)) return sendNak(kErrBusy);
#else
  if (interval != 0) return sendNak(kErrBusy);
#endif
  storeU16(tx().payload(), interval);
  reply(kMsgAck, 2);
}

void Session::sendSamples(uint16_t now) {
#if HUBWIRE_MAX_STREAMS > 0
  for (uint8_t i = 0; i < HUBWIRE_MAX_STREAMS; ++i) {
    Subscription& s = streams_[i];
    if (!s.due(now)) continue;
    ChannelInfo ch;
    if (!find(s.id, ch)) {
      s.id = 0;
      continue;
    }
    if (HubwireLarge<true, void>::send) {  // a sample too large for one frame goes as fragments
      uint8_t since[kSampleHeader];
      storeU16(since, s.since(now));
      if (HubwireLarge<true, void>::send(*this, kMsgSample, s.seq, s.id, ch, since, kSampleHeader, true)) s.sent(now);
      continue;
    }
    uint8_t* out = tx().payload();
    uint16_t len = ch.type.toWire(ch.data, out + kSampleHeader);
    if (portWritable(port_) < FrameWriter::wireSize8((uint8_t)(len + kSampleHeader))) continue;  // try again next update
    storeU16(out, s.since(now));
    send(kMsgSample, s.seq, s.id, (uint8_t)(len + kSampleHeader));
    s.sent(now);
  }
#else
  (void)now;
#endif
}

}  // namespace hubwire
