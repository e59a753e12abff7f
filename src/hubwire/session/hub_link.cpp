// The device's side of talking to the hub's own channels (hub_link.h, docs/PROTOCOL.md 10).
#include "session.h"

#include "../channels/hub_table.h"
#include "../wire/bytes.h"

namespace hubwire {

HubLink hubLink;

namespace {
const uint16_t kHubGiveUpMs = (uint16_t)HUBWIRE_HUB_RETRY_MS * HUBWIRE_HUB_TRIES;
}  // namespace

void deliverChunk(HubDone fn, const uint8_t* data, uint8_t len) {
  reinterpret_cast<HubChunk>(fn)(loadU16(data), loadU16(data + 2), data + kChunkHeader, (uint8_t)(len - kChunkHeader));
}

// ---- the session's two hooks (session.cpp) ----

// frame: the frame just received (true when it was the hub link's); else time to send and retry.
bool hubDispatch(Session& s, bool frame) {
  if (!s.hubMine()) return false;
  s.hubSessionCheck();
  if (frame) return s.hubFrame(s.received());
  s.hubPoll(s.ms());
  return false;
}

// Does the hub link serve this session? It does once begin() was given the table with the hub
// channels; the first question after that sets the link up.
bool Session::hubMine() {
  if (hubLink.owner == this) return true;
  HubTable t;
  flashCopy(&t, hubTable(), sizeof(t));
  // In a program with one table (sketchTable) the hub channels are that table's.
  if (!started_ || (!sketchTable.count && t.owner != table(&ChannelTable::channels))) return false;
  memset(&hubLink, 0, sizeof(hubLink));
  hubLink.owner = this;
  hubLink.channels = t.channels;
  hubLink.count = t.count;
  return true;
}

// A new hub session (the session took a new hub nonce): the hub binds again and numbers its events
// afresh.
void Session::hubSessionCheck() {
  HubLink& l = hubLink;
  if (!hubKnown_ || (l.hubKnown && hubNonce_ == l.hubNonce)) return;
  l.hubKnown = true;
  l.hubNonce = hubNonce_;
  l.bound = false;
  l.bind.state = kBindPending;
  l.eventValid = false;
  l.cValid = l.unsure = false;  // a new hub remembers nothing of the device's controls
}

// True when the frame was the hub link's to handle; false lets the session handle it as before.
bool Session::hubFrame(const Frame& f) {
  HubLink& l = hubLink;
  const uint8_t* p = f.payload;
  switch (f.type) {
    case kMsgHeartbeat:
      if (f.len >= kHeartbeatSize) {
        ++l.health.beats;
        l.health.sinceMs = loadU16(p + 2);
        l.health.crc = loadU16(p + 4);
        l.health.overflow = loadU16(p + 6);
        l.health.dropped = loadU16(p + 8);
      }
      return false;
    case kMsgChunk:  // an answer (longer than a request: session.cpp sends only those here)
    case kMsgAck:
    case kMsgNak:
    case kMsgResponse: {
      if (hubCleared(f)) return true;
      bool ours = l.queued && l.queue[l.head].tries && f.seq == l.headSeq && f.id == l.queue[l.head].id;
      if (ours) hubAnswer(f);
      return ours || f.type == kMsgResponse || f.type == kMsgChunk;  // a late answer to a retry is dropped
    }
    case kMsgEvent:
      if (!linked_) return sendNak(kErrNotLinked), true;
      hubEvent(f);
      return true;
    case kMsgControl:  // about to be answered (linked): the bind report is the hub link's
      if (f.id == 0) return hubBind(f), true;
      return false;
    default:
      return false;
  }
}

// Any answer to the chunk request sent in place of the head control (hubPoll()): the hub
// remembers none of the device's controls now, and the control goes out next, with a seq of its own.
bool Session::hubCleared(const Frame& f) {
  HubLink& l = hubLink;
  if (!l.clearing || f.seq != l.headSeq || f.id != 0) return false;
  l.clearing = false;
  l.queue[l.head].tries = 0;
  hubAnswered(kMsgChunk);
  return true;
}

// An answer to the head: it leaves the queue, then exactly one of its callbacks runs.
void Session::hubAnswer(const Frame& f) {
  HubLink& l = hubLink;
  if (!l.queued || !l.queue[l.head].tries || f.seq != l.headSeq || f.id != l.queue[l.head].id) return;
  HubLink::Entry e = l.queue[l.head];
  l.head = (uint8_t)((l.head + 1) % HUBWIRE_HUB_QUEUE);
  --l.queued;
  hubAnswered(e.type);
  uint8_t code = kOk;
  if (f.type == kMsgNak) {
    code = f.len == 1 && f.payload[0] != kOk ? f.payload[0] : (uint8_t)kErrBadLength;
  } else if (e.type == kMsgChunk) {
    if (f.type != kMsgChunk || f.len < kChunkHeader || loadU16(f.payload) != loadU16(e.data)) code = kErrBadLength;
  } else if (e.type == kMsgRequest) {
    ChannelInfo ch;
    hubFind(e.id, ch);
    code = f.type != kMsgResponse ? (uint8_t)kErrBadLength : (uint8_t)ch.type.check(f.payload, f.len);
    if (code == kOk) ch.type.fromWire(f.payload, f.len, ch.data);
  } else if (e.deliver) {  // a call answered with its return value
    ChannelInfo ch;
    hubFind(e.id, ch);
    if (f.type != kMsgResponse || f.len != scalarSize(ch.ret)) code = kErrBadLength;
  }
  if (code != kOk) {
    if (e.fail) e.fail(code);
  } else if (e.deliver) {
    if (e.done) e.deliver(e.done, f.payload, f.len);
  } else if (e.done) {
    e.done();
  }
}

// A hub event: stored and its onChange run once; a retry (same seq and id) is acknowledged again.
void Session::hubEvent(const Frame& f) {
  HubLink& l = hubLink;
  if (l.eventValid && f.seq == l.eventSeq && f.id == l.eventId) return reply(kMsgAck, 0);
  ChannelInfo ch;
  if (!hubFind(f.id, ch) || !(ch.access & kEventAccess)) return sendNak(kErrUnknownChannel);
  uint8_t code = ch.type.check(f.payload, f.len);
  if (code != kOk) return sendNak(code);
  ch.type.fromWire(f.payload, f.len, ch.data);
  if (ch.call) functionAt<void (*)()>(ch.call)();
  l.eventValid = true;
  l.eventSeq = f.seq;
  l.eventId = f.id;
  reply(kMsgAck, 0);
}

// The bind report: [version, status of hub id 1..N]. A control like any other: its answer is kept,
// so that a retry of it is answered again and not applied twice (session.cpp, handle()). Byte 0
// is not read: by the time the hook runs the session has written its NAK there (one buffer), and
// the length already tells this report from another layout.
void Session::hubBind(const Frame& f) {
  HubLink& l = hubLink;
  uint8_t code = f.len != 1 + l.count ? (uint8_t)kErrBadLength : (uint8_t)kOk;
  replyType_ = code == kOk ? kMsgAck : kMsgNak;
  replyLen_ = code == kOk ? 0 : 1;
  replyData_[0] = code;
  if (code != kOk) return sendNak(code);
  l.bound = true;
  l.bind.state = kBindOk;
  for (uint8_t k = 1; k <= l.count; ++k) {
    if (f.payload[k] == kOk) continue;
    l.bind.state = kBindFailed;
    l.bind.index = k;
    l.bind.code = f.payload[k];
    break;
  }
  reply(kMsgAck, 0);
}

// Sends the head once the hub has bound this session, retries it, and gives up after
// HUBWIRE_HUB_TRIES sends; a request that cannot be sent (no link, no bind report: an old hub)
// gives up as long after it was queued. A control never takes a seq the hub may still remember of
// an earlier one (txn.cpp, hubAnswered()); after a control left unanswered while an earlier one may
// be remembered, the next control's first tries send a chunk request instead, whose answer ends the
// hub's memory (hubCleared(), PROTOCOL.md 10.2).
void Session::hubPoll(uint16_t now) {
  HubLink& l = hubLink;
  while (l.queued) {
    HubLink::Entry& e = l.queue[l.head];
    bool canSend = linked_ && l.bound;
    bool giveUp;
    if (!e.tries) {
      giveUp = !canSend && (uint16_t)(now - e.at) >= kHubGiveUpMs;
    } else {
      if ((uint16_t)(now - e.at) < HUBWIRE_HUB_RETRY_MS) return;
      giveUp = e.tries >= HUBWIRE_HUB_TRIES;
    }
    if (giveUp) {
      if (e.type == kMsgControl && e.tries && !l.clearing) {  // the hub may have applied it
        l.unsure = l.cValid;
        l.cValid = true;
        l.cSeq = l.headSeq;
      }
      l.clearing = l.inFlight = false;
      HubFail fail = e.fail;
      l.head = (uint8_t)((l.head + 1) % HUBWIRE_HUB_QUEUE);
      --l.queued;
      if (fail) fail(kHubTimeout);
      continue;
    }
    if (!canSend && !e.tries) return;
    if (!e.tries) {
      l.clearing = e.type == kMsgControl && l.unsure;
      l.headSeq = takeTxn(e.type == kMsgControl && l.cValid ? l.cSeq : l.headSeq);
    }
    ++e.tries;  // while the link is down, a try passes unsent: the request still ends
    e.at = now;
    if (canSend) {
      l.inFlight = true;
      uint8_t* p = tx().payload();
      if (l.clearing) {
        p[0] = p[1] = p[2] = 0;  // offset 0, want 0: an empty chunk, whatever the hub describes
        send(kMsgChunk, l.headSeq, 0, kChunkRequestSize);
      } else {
        memcpy(p, e.data, e.len);
        send(e.type, l.headSeq, e.id, e.len);
      }
    }
    return;
  }
}

// The hub answered the head: what it remembers of the device's controls is now that control, or
// nothing (any other request ends that memory).
void Session::hubAnswered(uint8_t type) {
  HubLink& l = hubLink;
  l.cValid = type == kMsgControl;
  l.cSeq = l.headSeq;
  l.unsure = l.inFlight = false;
}

// ---- the sketch's requests ----

bool Session::hubFind(uint8_t id, ChannelInfo& ch) {
  if (id == 0 || id > hubLink.count) return false;
  flashCopy(&ch, &hubLink.channels[id - 1], sizeof(ch));
  return true;
}

HubLink::Entry* Session::hubPush(uint8_t id, uint8_t type, HubDone done, HubFail fail) {
  HubLink& l = hubLink;
  if (!started_ || l.queued >= HUBWIRE_HUB_QUEUE) return nullptr;
  HubLink::Entry& e = l.queue[(l.head + l.queued) % HUBWIRE_HUB_QUEUE];
  ++l.queued;
  e.id = id;
  e.type = type;
  e.len = 0;
  e.tries = 0;
  e.at = ms();
  e.done = done;
  e.fail = fail;
  e.deliver = nullptr;
  return &e;
}

bool Session::hubQueue(uint8_t type, const void* var, HubDone done, HubFail fail) {
  if (!hubTable() || !hubMine()) return false;
  uint8_t want = type == kMsgRequest ? kReadable : kWritable;
  for (uint8_t id = 1; id <= hubLink.count; ++id) {
    ChannelInfo ch;
    if (!hubFind(id, ch)) continue;
    if (ch.data != var || !(ch.access & want) || (ch.access & (kCallable | kEventAccess))) continue;
    if (type == kMsgControl && ch.type.wireSize() > HUBWIRE_HUB_MAX_VALUE) return false;
    HubLink::Entry* e = hubPush(id, type, done, fail);
    if (!e) return false;
    if (type == kMsgControl) e->len = (uint8_t)ch.type.toWire(var, e->data);  // the value as it is now
    return true;
  }
  return false;
}

bool Session::hubCall(const void* handle, const void* arg, uint8_t len, HubDone done, HubFail fail,
                      HubDeliver deliver) {
  if (!hubTable() || !hubMine()) return false;
  for (uint8_t id = 1; id <= hubLink.count; ++id) {
    ChannelInfo ch;
    if (!hubFind(id, ch)) continue;
    if (ch.data != handle || !(ch.access & kCallable)) continue;
    HubLink::Entry* e = hubPush(id, kMsgControl, done, fail);
    if (!e) return false;
    if (len) memcpy(e->data, arg, len);  // a scalar: its memory is its wire form
    e->len = len;
    e->deliver = deliver;
    return true;
  }
  return false;
}

bool Session::readHubDescriptor(uint16_t offset, HubChunk chunk, HubFail fail) {
  if (!hubTable() || !hubMine()) return false;
  HubLink::Entry* e = hubPush(0, kMsgChunk, reinterpret_cast<HubDone>(chunk), fail);
  if (!e) return false;
  storeU16(e->data, offset);
  e->data[2] = (uint8_t)(HUBWIRE_MAX_PAYLOAD - kChunkHeader);  // all the device takes
  e->len = kChunkRequestSize;
  e->deliver = &deliverChunk;
  return true;
}

}  // namespace hubwire
