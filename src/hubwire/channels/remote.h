// What a sketch expects of the hub, declared inside HUBWIRE_CHANNELS next to its own channels:
//
//   float setpoint;                           // the hub's "setpoint", read with hub.request()
//   uint16_t report;                          // the hub's "report", written with hub.write()
//   hubwire::RemoteAction<bool(float)> dock;  // the hub's action "dock", called with hub.call()
//   uint8_t mode;                             // the hub's event "mode", stored here as it comes
//
//   HUBWIRE_CHANNELS(channels, "thermo",
//     expose("temp", temp),
//     remote("setpoint", setpoint).unit("C"),
//     remote("report", report).writeOnly(),
//     remoteAction("dock", dock),
//     remoteEvent("mode", mode).onChange(modeChanged));
//
// They become the descriptor's "hub" list (hub ids 1..N in declaration order, docs/PROTOCOL.md 10)
// and a flash table the session reads (hub_table.h). A sketch that declares none pays nothing.
// Limits: one table with hub channels in a program, declared at file scope, next to at least one
// channel of the sketch's own (begin() refuses a table without one); values written or passed to
// an action fit HUBWIRE_HUB_MAX_VALUE bytes (a compile error says so).
#ifndef HUBWIRE_CHANNELS_REMOTE_H
#define HUBWIRE_CHANNELS_REMOTE_H

#include "dsl.h"

namespace hubwire {
namespace declare {

/// A value of the hub's that the sketch requests (hub.request(var)); with writable() it may also
/// write it (hub.write(var)), with writeOnly() only write it. Scalars, arrays, char[] strings, and
/// structs with a layout, as expose() takes them.
///   remote("setpoint", setpoint)
template <typename T>
constexpr auto remote(const char* name, T& var) -> decltype(expose(name, var).template as<kRemote>(kReadable)) {
  return expose(name, var).template as<kRemote>(kReadable);
}
template <typename T>
constexpr auto remote(const char* name, T& var, const char* layout)
    -> decltype(expose(name, var, layout).template as<kRemote>(kReadable)) {
  return expose(name, var, layout).template as<kRemote>(kReadable);
}

/// An action of the hub's the sketch calls (hub.call(handle, argument, onResult)); the handle's
/// signature gives the argument and the return value.
///   hubwire::RemoteAction<bool(float)> dock;   ...   remoteAction("dock", dock)
template <typename R, typename A>
constexpr Decl<A, kRemoteAction> remoteAction(const char* name, RemoteAction<R(A)>& a) {
  return checkValue<A, sizeof(A)>(), checkReturn<R>(),
         Decl<A, kRemoteAction>(name, nullptr, &a, TypeOf<A>::code, 0, TypeOf<R>::code, kCallable, nullptr, nullptr);
}
template <typename A>
constexpr Decl<A, kRemoteAction> remoteAction(const char* name, RemoteAction<void(A)>& a) {
  return checkValue<A, sizeof(A)>(),
         Decl<A, kRemoteAction>(name, nullptr, &a, TypeOf<A>::code, 0, kVoid, kCallable, nullptr, nullptr);
}
template <typename R>
constexpr Decl<NotNumeric, kRemoteAction> remoteAction(const char* name, RemoteAction<R()>& a) {
  return checkReturn<R>(),
         Decl<NotNumeric, kRemoteAction>(name, nullptr, &a, kVoid, 0, TypeOf<R>::code, kCallable, nullptr, nullptr);
}
inline constexpr Decl<NotNumeric, kRemoteAction> remoteAction(const char* name, RemoteAction<void()>& a) {
  return Decl<NotNumeric, kRemoteAction>(name, nullptr, &a, kVoid, 0, kVoid, kCallable, nullptr, nullptr);
}

/// An event the hub sends: each one is stored in var, exactly once and in order, then onChange()'s
/// function runs.
///   remoteEvent("mode", mode).onChange(modeChanged)
template <typename T>
constexpr auto remoteEvent(const char* name, T& var) -> decltype(expose(name, var).template as<kRemoteEvent>(kEventAccess)) {
  return expose(name, var).template as<kRemoteEvent>(kEventAccess);
}

}  // namespace declare
}  // namespace hubwire

#endif
