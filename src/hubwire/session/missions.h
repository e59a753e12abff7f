// Missions (docs/PROTOCOL.md 11): long actions the hub starts (C op 1) and may cancel (C op 2),
// whose progress the sketch reports from loop() and which end with a result, a failure code or as
// cancelled. The device sends each update as an `M` frame, stop and wait like events, numbered by
// the device's one transaction counter.
//
// A mission's RAM is its Mission object, owned by the sketch: the run number, flags, the latest
// progress value not yet sent, the final and the update in flight, each sized by its type. The
// session reaches the run time (missions.cpp) through three one-line hooks (HubwireMissions below):
// a sketch without missions links none of it.
#ifndef HUBWIRE_SESSION_MISSIONS_H
#define HUBWIRE_SESSION_MISSIONS_H

#include <stdint.h>
#include <string.h>

#include "../config.h"

namespace hubwire {

const uint8_t kMsgMission = 'M';  // device -> hub: a mission update

enum MissionOp : uint8_t { kMissionStart = 1, kMissionCancel = 2 };
enum MissionUpdate : uint8_t { kMissionProgress = 1, kMissionSucceeded = 2, kMissionFailed = 3, kMissionCancelled = 4 };
const uint8_t kMissionHeader = 2;  // an update's run number and kind

// What every mission holds, whatever its types; its values follow it (Mission below).
struct MissionState {
  enum Flags : uint8_t { kRunning = 1, kProgressPending = 2, kFinalPending = 4 };
  uint8_t id_;     // its channel id, known from its first start
  uint8_t run_;    // the latest run number (1..255), 0 before the first
  uint8_t flags_;  // Flags
  uint8_t final_;  // the final's kind (MissionUpdate) while kFinalPending

  /// Is a run going (started by the hub, not yet finished, failed or cancelled)?
  ///   if (drive.running()) advance();
  bool running() const { return flags_ & kRunning; }
  /// The latest run's number (1..255; 0 before the first start).
  ///   uint8_t r = drive.run();
  uint8_t run() const { return run_; }
};

// Capped at 255 so that a type too wide for a mission is refused by the declaration's
// static_assert (a scalar), not by the compiler's overflow of this byte.
template <typename T>
struct MissionSize {
  static const uint8_t value = sizeof(T) > 255 ? 255 : (uint8_t)sizeof(T);
};
template <>
struct MissionSize<void> {
  static const uint8_t value = 0;
};
template <uint8_t A, uint8_t B>
struct MissionMax {
  static const uint8_t value = A > B ? A : B;
};

// The values after the state: the progress not yet sent, the final (result or failure code) not
// yet sent, and the update in flight (its run, kind and value), kept for its retries while the next
// ones are reported. missions.cpp finds them by the sizes stored in flash (MissionCalls).
template <uint8_t ProgressSize, uint8_t ResultSize>
struct MissionValues : MissionState {
  uint8_t progress_[ProgressSize ? ProgressSize : 1];
  uint8_t result_[ResultSize ? ResultSize : 1];
  uint8_t sent_[kMissionHeader + MissionMax<MissionMax<ProgressSize, ResultSize>::value, 1>::value];
};

/// A mission, by its signature Result(Goal) and its progress type (void allowed in each):
///   hubwire::Mission<float(float), float> drive;   // goal metres, result metres, progress metres
///   hubwire::Mission<void(), void> home;           // no goal, no result, progress says "running"
template <typename Signature, typename Progress = void>
class Mission;
template <typename R, typename G, typename P>
class Mission<R(G), P> : public MissionValues<MissionSize<P>::value, MissionSize<R>::value> {
 public:
  typedef R Result;
  typedef P ProgressType;
};
template <typename R, typename P>
class Mission<R(), P> : public MissionValues<MissionSize<P>::value, MissionSize<R>::value> {
 public:
  typedef R Result;
  typedef P ProgressType;
};

// The functions a mission declares, kept in flash as its channel's "call" (channels/mission.h):
// start first, so that the thunk of a control calls it, then cancel and the value sizes.
template <typename Start>
struct MissionCalls {
  Start start;
  void (*cancel)();
  uint8_t progressSize, resultSize;
};
typedef MissionCalls<void (*)()> AnyMissionCalls;

// The run time's own state, one for the program (missions.cpp): the update in flight (at most one
// for all missions), the device's transaction counter when no hub link keeps it, and where the
// round robin goes on.
struct MissionLink {
  uint8_t counter;  // the last seq numbered here (without hub channels: events and missions)
  uint8_t id;       // the mission whose update is in flight (0: none)
  uint8_t seq, len;  // ... its seq and payload length (the payload is that mission's sent_)
  uint16_t sentAt;  // when it was last sent (16-bit ms)
  uint8_t next;     // the round robin: the channel id to look at first
  bool pending;     // some mission has an update not yet sent
  bool linked;      // the link as the last poll saw it (a new link sends the update in flight at once)
};
extern MissionLink missionLink;

// Stores a report of the sketch (hub.progress(), finish(), fail()); false when no run is going.
bool missionReport(MissionState& m, uint8_t kind, const void* value, uint8_t len, uint8_t* slot);

// The session's hooks: what it asks the run time (missions.cpp) to do with the frame it holds.
enum MissionHook : uint8_t { kMissionPoll, kMissionFrame, kMissionAck };
class Session;
bool missionDispatch(Session& s, uint8_t what);

}  // namespace hubwire

// Paying only for what is declared, as for hub channels (channels/hub_table.h): the session calls
// the run time through HubwireMissions<true, void>::dispatch, which the library defines weakly as
// nullptr (session/mission_flag.cpp) and HUBWIRE_CHANNELS defines again, as &missionDispatch, only
// for a table that declares a mission. Nothing else refers to the run time, so a sketch without
// missions links none of its code or RAM. In the global namespace, where the macro can specialise
// it; a table without missions specialises <false, its own tag>, which nothing reads.
template <bool Declared, typename Tag>
struct HubwireMissions {
  static bool (*const dispatch)(::hubwire::Session& s, uint8_t what);
};
template <>
bool (*const HubwireMissions<true, void>::dispatch)(::hubwire::Session& s, uint8_t what);

#endif
