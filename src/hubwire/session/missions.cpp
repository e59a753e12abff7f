// The device's side of missions (missions.h, docs/PROTOCOL.md 11).
#include "session.h"

#include "../channels/hub_table.h"

namespace hubwire {

MissionLink missionLink;

namespace {
uint8_t atLeastOne(uint8_t n) { return n ? n : 1; }
}  // namespace

// ---- the session's three hooks (session.cpp) ----
bool missionDispatch(Session& s, uint8_t what) {
  if (what == kMissionPoll) return s.missionPoll(s.ms()), false;
  return what == kMissionFrame ? s.missionFrame(s.received()) : s.missionAck(s.received());
}

bool missionReport(MissionState& m, uint8_t kind, const void* value, uint8_t len, uint8_t* slot) {
  if (!(m.flags_ & MissionState::kRunning)) return false;
  if (len) memcpy(slot, value, len);
  if (kind == kMissionProgress) {
    m.flags_ |= MissionState::kProgressPending;
  } else {  // a final takes the place of a progress not yet sent, and nothing follows it
    m.flags_ = (uint8_t)((m.flags_ & ~(MissionState::kRunning | MissionState::kProgressPending)) |
                         MissionState::kFinalPending);
    m.final_ = kind;
  }
  missionLink.pending = true;
  return true;
}

// ---- the hub's R and C on a mission channel (the session's hook in handle()) ----

// True when f was for a mission: then it is answered here.
bool Session::missionFrame(const Frame& f) {
  ChannelInfo ch;
  if ((f.type != kMsgControl && f.type != kMsgRequest) || !find(f.id, ch) || !(ch.access & kMissionAccess))
    return false;
  MissionState& m = *static_cast<MissionState*>(ch.data);
  uint8_t* out = tx().payload();  // the same bytes as f.payload: read before written
  if (f.type == kMsgRequest) {
    if (f.len != 0) return sendNak(kErrBadLength), true;
    out[0] = m.run_;
    // running for the hub until its final is sent: exactly when a start is refused BUSY
    out[1] = (m.flags_ & (MissionState::kRunning | MissionState::kFinalPending)) ? 1 : 0;
    return reply(kMsgResponse, 2), true;
  }
  uint8_t code = kOk;
  if (f.len == 0) {
    code = kErrBadLength;
  } else if (f.payload[0] == kMissionStart) {
    code = missionStart(f, ch, m);
  } else if (f.payload[0] != kMissionCancel) {
    code = kErrBadValue;
  } else if (f.len != 2) {
    code = kErrBadLength;
  } else if (!m.running() || f.payload[1] != m.run_) {
    out[0] = 0;
  } else {
    AnyMissionCalls calls;
    flashCopy(&calls, ch.call, sizeof(calls));
    calls.cancel();
    // The sketch may have ended the run itself inside cancel; otherwise it ends as cancelled.
    missionReport(m, kMissionCancelled, nullptr, 0, nullptr);
    out[0] = 1;
  }
  uint8_t type = kMsgResponse, len = 1;
  if (code != kOk) {
    type = kMsgNak;
    out[0] = code;
  }
  // The answer is remembered for a retry of this control.
  replyType_ = type;
  replyLen_ = len;
  replyData_[0] = out[0];
  reply(type, len);
  return true;
}

// A start: the goal checked as a control's value, then the sketch's start function called with
// the run already numbered (it may report, or even finish, at once). out: the run number.
uint8_t Session::missionStart(const Frame& f, const ChannelInfo& ch, MissionState& m) {
  // A run that has ended but whose final has not been sent is still running for the hub.
  if (m.flags_ & (MissionState::kRunning | MissionState::kFinalPending)) return kErrBusy;
  const uint8_t* goal = f.payload + 1;
  uint8_t len = (uint8_t)(f.len - 1);
  uint8_t code = ch.type.code == kVoid ? (len ? (uint8_t)kErrBadLength : (uint8_t)kOk) : (uint8_t)ch.type.check(goal, len);
  if (code == kOk && (ch.flags & kHasRange)) {
    ChannelLimits lim;
    flashCopy(&lim, ch.limits, sizeof(lim));
    if (!lim.inRange(goal, &lim.min, &lim.max)) code = kErrOutOfRange;
  }
  if (code != kOk) return code;
  uint8_t before = m.run_;
  m.id_ = f.id;
  m.run_ = (uint8_t)(m.run_ == 255 ? 1 : m.run_ + 1);
  m.flags_ = MissionState::kRunning;
  uint8_t scratch[HUBWIRE_LARGEST_SCALAR];
  if (!ch.thunk(ch.call, goal, scratch)) {
    m.run_ = before;
    m.flags_ = 0;  // whatever the refusing start function reported is dropped with its run
    return kErrRejected;
  }
  tx().payload()[0] = m.run_;
  return kOk;
}

// ---- the M updates ----

// The next update's seq: never the previous update's, which the hub remembers (txn.cpp).
uint8_t Session::missionTake() { return takeTxn(missionLink.seq); }

// Each update(): the update in flight retried, or the next one sent.
void Session::missionPoll(uint16_t now) {
  MissionLink& l = missionLink;
  if (!linked_) {
    l.linked = false;
  } else if (l.id) {
    if (!l.linked || (uint16_t)(now - l.sentAt) >= HUBWIRE_EVENT_RETRY_MS) missionSend();
    l.linked = true;
  } else {
    l.linked = true;
    const uint8_t count = table(&ChannelTable::count);
    for (uint8_t k = 0; l.pending && k < count; ++k) {
      uint8_t id = (uint8_t)((l.next + k) % count + 1);
      ChannelInfo ch;
      find(id, ch);
      if (!(ch.access & kMissionAccess)) continue;
      MissionState& m = *static_cast<MissionState*>(ch.data);
      if (!(m.flags_ & (MissionState::kProgressPending | MissionState::kFinalPending))) continue;
      AnyMissionCalls calls;
      flashCopy(&calls, ch.call, sizeof(calls));
      uint8_t* values = reinterpret_cast<uint8_t*>(&m) + sizeof(MissionState);
      uint8_t* result = values + atLeastOne(calls.progressSize);
      uint8_t* sent = result + atLeastOne(calls.resultSize);
      sent[0] = m.run_;
      if (m.flags_ & MissionState::kProgressPending) {
        sent[1] = kMissionProgress;
        l.len = calls.progressSize;
        memcpy(sent + kMissionHeader, values, l.len);
        m.flags_ &= (uint8_t)~MissionState::kProgressPending;
      } else {
        sent[1] = m.final_;
        l.len = m.final_ == kMissionSucceeded ? calls.resultSize : m.final_ == kMissionFailed ? 1 : 0;
        memcpy(sent + kMissionHeader, result, l.len);
        m.flags_ &= (uint8_t)~MissionState::kFinalPending;
      }
      l.len = (uint8_t)(l.len + kMissionHeader);
      l.id = id;
      l.next = id;  // the next look starts after this mission
      l.seq = missionTake();
      missionSend();
      break;
    }
    if (!l.id) l.pending = false;
  }
}

void Session::missionSend() {
  MissionLink& l = missionLink;
  ChannelInfo ch;
  find(l.id, ch);
  AnyMissionCalls calls;
  flashCopy(&calls, ch.call, sizeof(calls));
  const uint8_t* sent = reinterpret_cast<const uint8_t*>(ch.data) + sizeof(MissionState) +
                        atLeastOne(calls.progressSize) + atLeastOne(calls.resultSize);
  memcpy(tx().payload(), sent, l.len);
  send(kMsgMission, l.seq, l.id, l.len);
  l.sentAt = ms();
}

// An ACK or NAK for the update in flight ends it (a NAK too: the hub has seen it).
bool Session::missionAck(const Frame& f) {
  MissionLink& l = missionLink;
  if (!l.id || f.seq != l.seq || f.id != l.id) return false;
  l.id = 0;
  l.pending = true;  // look again: others may have waited behind it
  return true;
}

}  // namespace hubwire
