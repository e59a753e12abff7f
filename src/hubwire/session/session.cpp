#include "session.h"

#include "../channels/hub_table.h"
#include "../features.h"
#include "../wire/bytes.h"
#include "hooks.h"

namespace hubwire {

namespace {
const uint8_t kMaxBytesPerUpdate = 128;  // keeps update() short when a burst arrives
const uint8_t kStalledFrameMs = 50;      // no byte of a frame for this long: the sender stopped
}  // namespace

Session::Session(const Port& port)
    : SessionState(),  // all zero
      port_(port) {
  peerMax_ = kHelloSize;  // all a hub not yet heard is sure to accept (PROTOCOL.md 3.1)
  // lostAfterMs_ is set by the hello that brings the link up, before anything reads it.
}

bool Session::begin(const ChannelTable& channels, uint32_t seed) {
  started_ = false;
  // A program with one table starts that one only; one with several notes where it is.
  if (sketchTable.count) {
    if (&channels != sketchTableAt) return false;
  } else {
    table_ = &channels;
  }
  const uint8_t count = table(&ChannelTable::count);
  if (count == 0) return false;
  // Events learn their ids: emit() names the event by its handle.
  const ChannelInfo* record = table(&ChannelTable::channels);
  for (uint8_t id = 1; uses(kUsesEvents) && id <= count; ++id, ++record) {
    // two fields read, not the whole record
    if (flashRead(&record->access) & kEventAccess) *(uint8_t*)flashRead(&record->data) = id;
  }
  nonce_ = seed;  // until drawNonce() mixes in the moment the hub is first heard
  nonceDrawn_ = false;
  started_ = true;
  linked_ = false;
  lastSent_ = ms();  // the first announcement follows one interval after boot
  return true;
}

// Drawn once per boot, at the first hub hello (or the first announcement if none came first):
// the per-boot seed, the fast clock (its fast bits reversed into the top byte, away from a boot
// counter's) and the hub's random nonce, which differs for every connection even where a simulated
// or freshly powered board repeats everything else. Mixing by xor, byte by byte, is enough: any one
// part differing makes the nonce differ, and the hub needs no more than that (docs/PROTOCOL.md 4).
void Session::drawNonce(const uint8_t* hubNonce) {
  uint32_t t = portMicros(port_);
  uint8_t* n = (uint8_t*)&nonce_;
  uint8_t any = 0;
  for (uint8_t i = 4; i--; t >>= 8) any |= n[i] ^= (uint8_t)(hubNonce[i] ^ (uint8_t)t);
  if (!any) n[0] = 1;  // never 0: the protocol reserves it
  nonceDrawn_ = true;
}

void Session::update() {
  if (!started_) return;
  uint8_t i = 0;
  uint16_t start = ms();  // when the frames read below are taken to have come
  Port port = port_;  // the stream kept in registers across the loop: no loads per byte
  for (; i < kMaxBytesPerUpdate; ++i) {
    int c = portRead(port);
    if (c < 0) break;
    if (rx_.feed((uint8_t)c, rxBuf(), kRxCapacity)) {
      lastRx_ = start;
      handle(received());
    }
  }
  uint16_t now = ms();
  if (i) lastByte_ = now;
  if (linked_ && (uint16_t)(now - lastRx_) >= lostAfterMs_) loseLink(now);
  // Frames are received and sent in one buffer. Answers are sent while no frame is arriving; a
  // frame of our own waits for one that is half here, unless that one has stalled (a hub that
  // died mid-frame), which is then dropped and counted.
  if (!rx_.idle()) {
    if ((uint16_t)(now - lastByte_) < kStalledFrameMs) return;
    rx_.reset();
    ++rx_.counters.dropped;
  }
  hubHook(*this, false);  // sends and retries the sketch's requests
  missionHook(*this, kMissionPoll);  // sends and retries mission updates (missions.cpp)
  if (!linked_) {
    if ((uint16_t)(now - lastSent_) >= HUBWIRE_ANNOUNCE_MS) {
      lastSent_ = now;
      sendHello(kHelloDevice);
    }
    return;
  }
  if (!beatSent_ || (uint16_t)(now - lastSent_) >= HUBWIRE_HEARTBEAT_MS) sendHeartbeat(now);
  if (uses(kUsesEvents) && events_.due(now)) sendEvent(now);
  if (uses(kUsesStreams)) sendSamples(now);
}

void Session::handle(const Frame& f) {
  switch (f.type) {
    case kMsgHello:
      return onHello(f);
    case kMsgHeartbeat:
      if (!linked_) return sendHello(kHelloDevice);  // the hub thinks we are linked: invite it to handshake again
      hubHook(*this, true);  // the hub link notes the hub's health (hub_link.cpp)
      return;
    case kMsgAck:
    case kMsgNak:
      return onAck(f, f.type == kMsgNak);
    case kMsgChunk:
      // A request is 3 bytes, an answer (to the device's own J, hub_link.cpp) at least 4: an answer
      // is no hub transaction, so it passes by the link check and the duplicate memory.
      if (f.len > kChunkRequestSize && f.len != 0xFF && hubHook(*this, true)) return;
      break;
    case kMsgRequest:
    case kMsgControl:
    case kMsgSubscribe:
      break;
    default:
      if (HubwireLarge<true, void>::receive && f.type == kMsgFragment) return HubwireLarge<true, void>::receive(*this, f);
      if (hubHook(*this, true)) return;  // hub events, answers to the device's requests
      ++rx_.counters.dropped;
      return sendNak(kErrUnknownType);
  }
  if (!linked_) return sendNak(kErrNotLinked);
  bool control = f.type == kMsgControl;
  // Another control of the hub (one at a time, 4.4; 0xFF: the reassembled one itself): a control
  // half reassembled will not be retried, so no later message may complete it (fragments.cpp keeps
  // a partial, or a whole one answered already, for its retry).
  if (HubwireLarge<true, void>::state && control && f.len != 0xFF) HubwireLarge<true, void>::state->total = 0;
  if (control && lastTxnControl_ && f.seq == lastTxnSeq_ && f.id == lastTxnId_) {
    // a retried control: answer again, do not apply twice (without returns the answer kept is
    // one byte, an ACK's or a NAK's code)
    memcpy(tx().payload(), replyData_, uses(kUsesReturns) ? replyLen_ : 1);
    return reply(replyType_, replyLen_);
  }
  lastTxnControl_ = control;
  lastTxnSeq_ = f.seq;
  lastTxnId_ = f.id;
  if (missionHook(*this, kMissionFrame)) return;  // a mission's start, cancel or state
  switch (f.type) {
    case kMsgControl:
      return onControl(f);
    case kMsgRequest:
      return onRequest(f);
    case kMsgChunk:
      return onChunk(f);
    default:
      return onSubscribe(f);
  }
}

void Session::onHello(const Frame& f) {
  if (f.len < kHelloSize) {
    ++rx_.counters.dropped;
    sendNak(kErrBadLength);
    return;
  }
  // Everything is read before the answer is written: it is built in the same buffer.
  const uint8_t* p = f.payload;
  uint8_t version = p[0], flags = p[1];
  uint32_t nonce = loadU32(p + 2);
  uint16_t max = loadU16(p + 6);
  uint16_t beat = loadU16(p + 8);
  if (!nonceDrawn_) drawNonce(p + 2);
  bool fromHub = version == kProtocolVersion && !(flags & kHelloDevice);
  // A peer takes at least a hello (16 bytes); smaller claims would make chunk sizes wrap. Known
  // before the answer, which carries the digest only if this hub accepts it.
  if (fromHub) peerMax_ = (uint8_t)(max > HUBWIRE_MAX_PAYLOAD ? HUBWIRE_MAX_PAYLOAD : max < kHelloSize ? kHelloSize : max);
  if (!(flags & kHelloReply)) sendHello(kHelloDevice | kHelloReply);
  if (!fromHub) return;  // the hub reports the mismatch
  if (!hubKnown_ || nonce != hubNonce_) newHubSession(nonce);
  // Times are 16-bit milliseconds: the timeout must stay below 65.5 s.
  const uint16_t kMaxBeat = 65535u / HUBWIRE_LOST_AFTER_BEATS;
  lostAfterMs_ = (uint16_t)((beat < 10 ? 10 : beat > kMaxBeat ? kMaxBeat : beat) * HUBWIRE_LOST_AFTER_BEATS);
  if (!linked_) {
    linked_ = true;
    beatSent_ = false;
    // Send the head event again right away, with its seq: the hub may have delivered it already.
    events_.retryNow(ms());
    if (onLinkUp_) onLinkUp_();
  }
}

void Session::newHubSession(uint32_t nonce) {
  hubKnown_ = true;
  hubNonce_ = nonce;
  lastTxnControl_ = false;
#if HUBWIRE_MAX_STREAMS > 0
  if (uses(kUsesStreams)) streams_.clear();
#endif
}

void Session::loseLink(uint16_t now) {
  linked_ = false;
  applyFailsafes();
#if HUBWIRE_MAX_STREAMS > 0
  if (uses(kUsesStreams)) streams_.clear();
#endif
  lastSent_ = now;  // the next announcement one interval after the loss
  if (onLinkLost_) onLinkLost_();
}

void Session::onAck(const Frame& f, bool nak) {
  (void)nak;  // a NAKed event is not retried either: the hub has seen it and refused it
  if (missionHook(*this, kMissionAck)) return;  // a mission update's answer
  if (uses(kUsesEvents) && events_.acked(f.seq, f.id)) return;
  hubHook(*this, true);  // an answer to the device's own request?
}

void Session::onChunk(const Frame& f) {
  if (f.len != kChunkRequestSize) return sendNak(kErrBadLength);  // a reassembled one (0xFF)
  uint16_t offset = loadU16(f.payload);
  uint8_t want = f.payload[2];
  uint16_t total = table(&ChannelTable::jsonLength);
  if (offset > total) return sendNak(kErrBadOffset);
  uint16_t n = (uint16_t)(maxOut() - kChunkHeader);  // maxOut() >= 16: never wraps
  if (want < n) n = want;
  if (total - offset < n) n = (uint16_t)(total - offset);
  uint8_t* out = tx().payload();  // where the request is: its offset is already the answer's
  storeU16(out + 2, total);
  flashCopy(out + kChunkHeader, table(&ChannelTable::json) + offset, n);
  reply(kMsgChunk, (uint8_t)(kChunkHeader + n));
}

bool Session::emitRaw(uint8_t id, const void* value, uint8_t size) {
  if (!started_ || id == 0) return false;
  return events_.push(id, value, size);
}

void Session::sendEvent(uint16_t now) {
  // A new head's seq: from the one counter where missions or hub channels share it (txn.cpp),
  // never the previous event's; else the queue's own ++seq.
  if (sharedCounter() && !events_.inFlight()) events_.nextSeqIs(takeTxn(events_.seq()));
  const EventQueue::Entry& e = events_.send(now);
  memcpy(tx().payload(), e.data, sizeof(e.data));  // the whole slot, a fixed size: copied inline
  send(kMsgEvent, events_.seq(), e.id, e.len);
}

void Session::sendHello(uint8_t flags) {
  if (!nonceDrawn_) drawNonce((const uint8_t*)&hubNonce_);  // no hub heard this boot: 0, or any earlier hub's
  uint8_t* p = tx().payload();
  p[0] = kProtocolVersion;
  p[1] = (uint8_t)(flags | kHelloSeqRules | (HUBWIRE_HAS_F64 ? kHelloF64 : 0));
  memcpy(p + 2, &nonce_, 4);  // as it is in memory: that is its wire form (config.h)
  // The fixed fields and the digest, just before the JSON in flash (channels/tables.h); the digest
  // goes to a hub that accepts it: one that accepts only 16 bytes gets the hello it knows.
  const uint8_t kFixed = HUBWIRE_MAX_PAYLOAD >= kHelloDigestEnd ? kHelloFixed + kDigestSize : kHelloFixed;
  flashCopy(p + kHelloSize - kHelloFixed, table(&ChannelTable::json) - kDigestSize - kHelloFixed, kFixed);
  send(kMsgHello, 0, 0, maxOut() >= kHelloDigestEnd ? kHelloDigestEnd : kHelloSize);
}

void Session::sendHeartbeat(uint16_t now) {
  uint8_t* p = tx().payload();
  ++beatCounter_;
  storeU16(p, beatCounter_);
  uint16_t since = (uint16_t)(now - lastSent_);  // then cleared: smaller than a conditional
  if (!beatSent_) since = 0;  // the first since the link came up
  storeU16(p + 2, since);
  static_assert(sizeof(LinkCounters) == 6, "crc, overflow, dropped: the heartbeat's order");
  memcpy(p + 4, &rx_.counters, 6);
  send(kMsgHeartbeat, (uint8_t)beatCounter_, 0, kHeartbeatSize);
  lastSent_ = now;
  beatSent_ = true;
}

void Session::sendNak(uint8_t code) {
  tx().payload()[0] = code;
  reply(kMsgNak, 1);
}

// The frame answered is still in the buffer: its header lies before the payload the answer is
// built in (a reassembled value's last fragment carries its seq and id). Read there, at constant
// addresses: a frame's address passed to every answer cost more.
void Session::reply(uint8_t type, uint8_t len) { send(type, frameBuf_[2], frameBuf_[3], len); }

}  // namespace hubwire
