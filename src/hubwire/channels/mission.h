// mission(): a long action the hub starts with a goal, whose progress the sketch reports from
// loop() and which ends with a result, a failure code, or as cancelled (session/missions.h):
//
//   hubwire::Mission<float(float), float> drive;   // Result(Goal), Progress; void allowed in each
//   bool startDrive(float metres) { ...; return true; }   // or void; false: the hub gets REJECTED
//   void cancelDrive() { ...stop... }                       // then the run ends as cancelled
//   HUBWIRE_CHANNELS(channels, "rover",
//     mission("drive", drive, startDrive, cancelDrive).unit("m").progressMax(2.0f));
//
// The goal is a scalar (or none), with range() checked as a control's value; the result and the
// progress are scalars (or none), each fitting one frame with its 2-byte header.
#ifndef HUBWIRE_CHANNELS_MISSION_H
#define HUBWIRE_CHANNELS_MISSION_H

#include "../session/missions.h"
#include "dsl.h"

namespace hubwire {

inline bool callNoArgChecked(const void* call, const uint8_t*, uint8_t*) { return functionAt<bool (*)()>(call)(); }

namespace declare {

// The types a goal, result or progress may have: scalars (and void), told apart before TypeOf
// (whose test of signedness does not compile for a struct), so that the message says why.
template <typename T>
struct IsWireScalar {
  static const bool value = false;
};
#define HUBWIRE_WIRE_SCALAR(T)         \
  template <>                          \
  struct IsWireScalar<T> {             \
    static const bool value = true;    \
  };
HUBWIRE_WIRE_SCALAR(bool)
HUBWIRE_WIRE_SCALAR(char)
HUBWIRE_WIRE_SCALAR(signed char)
HUBWIRE_WIRE_SCALAR(unsigned char)
HUBWIRE_WIRE_SCALAR(short)
HUBWIRE_WIRE_SCALAR(unsigned short)
HUBWIRE_WIRE_SCALAR(int)
HUBWIRE_WIRE_SCALAR(unsigned)
HUBWIRE_WIRE_SCALAR(long)
HUBWIRE_WIRE_SCALAR(unsigned long)
HUBWIRE_WIRE_SCALAR(long long)
HUBWIRE_WIRE_SCALAR(unsigned long long)
HUBWIRE_WIRE_SCALAR(float)
HUBWIRE_WIRE_SCALAR(double)
#undef HUBWIRE_WIRE_SCALAR

template <typename T, bool Scalar = IsWireScalar<T>::value>
struct MissionTypeOf {
  static constexpr TypeCode code() { return TypeOf<T>::code; }
};
template <typename T>
struct MissionTypeOf<T, false> {  // void, or refused by checkMission()
  static constexpr TypeCode code() { return kVoid; }
};

template <typename R, typename P>
constexpr bool checkMission() {
  static_assert(MissionSize<R>::value == 0 || (IsWireScalar<R>::value && MissionTypeOf<R>::code() != kVoid),
                "mission result: Hubwire carries bool, 8/16/32-bit integers, float and double (or void)");
  static_assert(MissionSize<P>::value == 0 || (IsWireScalar<P>::value && MissionTypeOf<P>::code() != kVoid),
                "mission progress: Hubwire carries bool, 8/16/32-bit integers, float and double (or void)");
  static_assert(kMissionHeader + MissionSize<R>::value <= HUBWIRE_MAX_PAYLOAD,
                "mission result larger than HUBWIRE_MAX_PAYLOAD - 2 (an update's header): raise it");
  static_assert(kMissionHeader + MissionSize<P>::value <= HUBWIRE_MAX_PAYLOAD,
                "mission progress larger than HUBWIRE_MAX_PAYLOAD - 2 (an update's header): raise it");
  return true;
}

template <typename Start, typename R, typename P>
constexpr MissionCalls<Start> missionCalls(Start start, void (*cancel)()) {
  return MissionCalls<Start>{start, cancel, MissionSize<P>::value, MissionSize<R>::value};
}

/// A mission with a goal: start(goal) runs inside hub.update() and returns at once (false refuses
/// it: NAK REJECTED); cancel() stops the work when the hub cancels the run.
///   mission("drive", drive, startDrive, cancelDrive)
template <typename R, typename G, typename P>
constexpr Decl<G, kMission, MissionCalls<bool (*)(G)> > mission(const char* name, Mission<R(G), P>& m,
                                                                 bool (*start)(G), void (*cancel)()) {
  static_assert(IsWireScalar<G>::value, "mission goal: Hubwire carries bool, 8/16/32-bit integers, float and double (or none)");
  return checkValue<G, sizeof(G) + 1>(), checkMission<R, P>(),
         Decl<G, kMission, MissionCalls<bool (*)(G)> >(name, nullptr, static_cast<MissionState*>(&m), TypeOf<G>::code, 0,
                                                        MissionTypeOf<R>::code(), kMissionAccess,
                                                        missionCalls<bool (*)(G), R, P>(start, cancel),
                                                        &callChecked<G>, 0, 0, MissionTypeOf<P>::code());
}
template <typename R, typename G, typename P>
constexpr Decl<G, kMission, MissionCalls<void (*)(G)> > mission(const char* name, Mission<R(G), P>& m,
                                                                 void (*start)(G), void (*cancel)()) {
  static_assert(IsWireScalar<G>::value, "mission goal: Hubwire carries bool, 8/16/32-bit integers, float and double (or none)");
  return checkValue<G, sizeof(G) + 1>(), checkMission<R, P>(),
         Decl<G, kMission, MissionCalls<void (*)(G)> >(name, nullptr, static_cast<MissionState*>(&m), TypeOf<G>::code, 0,
                                                        MissionTypeOf<R>::code(), kMissionAccess,
                                                        missionCalls<void (*)(G), R, P>(start, cancel),
                                                        &callVoid<G>, 0, 0, MissionTypeOf<P>::code());
}
/// A mission without a goal.
///   mission("home", home, startHoming, stopHoming)
template <typename R, typename P>
constexpr Decl<NotNumeric, kMission, MissionCalls<bool (*)()> > mission(const char* name, Mission<R(), P>& m,
                                                                         bool (*start)(), void (*cancel)()) {
  return checkMission<R, P>(),
         Decl<NotNumeric, kMission, MissionCalls<bool (*)()> >(name, nullptr, static_cast<MissionState*>(&m), kVoid, 0,
                                                                MissionTypeOf<R>::code(), kMissionAccess,
                                                                missionCalls<bool (*)(), R, P>(start, cancel),
                                                                &callNoArgChecked, 0, 0, MissionTypeOf<P>::code());
}
template <typename R, typename P>
constexpr Decl<NotNumeric, kMission, MissionCalls<void (*)()> > mission(const char* name, Mission<R(), P>& m,
                                                                         void (*start)(), void (*cancel)()) {
  return checkMission<R, P>(),
         Decl<NotNumeric, kMission, MissionCalls<void (*)()> >(name, nullptr, static_cast<MissionState*>(&m), kVoid, 0,
                                                                MissionTypeOf<R>::code(), kMissionAccess,
                                                                missionCalls<void (*)(), R, P>(start, cancel),
                                                                &callPlain, 0, 0, MissionTypeOf<P>::code());
}

// The missions' hook (session/missions.h) for a table that declares one (declare.h).
template <bool Missions>
struct MissionHookOf {
  static constexpr bool (*dispatch())(Session&, uint8_t) { return nullptr; }
};
template <>
struct MissionHookOf<true> {
  static constexpr bool (*dispatch())(Session&, uint8_t) { return &missionDispatch; }
};
constexpr bool anyMissionIn(const List<>&) { return false; }
template <typename H, typename... R>
constexpr bool anyMissionIn(const List<H, R...>& l) {
  return l.head.isMission() || anyMissionIn(l.tail);
}
template <typename... T>
constexpr bool anyMission(const List<T...>& l) { return anyMissionIn(copyOf(l)); }  // dsl.h: copyOf

}  // namespace declare
}  // namespace hubwire

#endif
