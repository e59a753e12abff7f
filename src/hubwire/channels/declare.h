// Channel declarations the compiler works out: a sketch lists its channels once, at file scope,
//
//   HUBWIRE_CHANNELS(channels, "rover",
//     expose("speed", speed).writable().range(-1.0f, 1.0f).unit("m/s").failsafe(0.0f),
//     control("led", setLed),
//     event("bumper", bumper));
//
// and gets, as constants in flash, the descriptor JSON (docs/PROTOCOL.md 7) and one record per
// channel (channel.h) that the session reads when the hub addresses the channel. Nothing is built
// or checked on the board: a declaration that cannot work fails to compile, saying why.
#ifndef HUBWIRE_CHANNELS_DECLARE_H
#define HUBWIRE_CHANNELS_DECLARE_H

// One job a header: the declarations a sketch writes (dsl.h; Lists: list_dsl.h; missions: mission.h;
// what it expects of the hub: remote.h), the JSON they become (json.h; a struct's layout: layout.h),
// the flash tables with their checks (tables.h) and the hub channels' table (hub_table.h).
#include "dsl.h"
#include "mission.h"
#include "list_dsl.h"
#include "remote.h"
#include "tables.h"
#include "hub_table.h"
#include "report.h"
#include "steps.h"
#include "../session/fragments.h"

// The <false, tag> specialisations below exist only to keep the macro's text the same for every
// sketch: nothing reads them.
#if defined(__GNUC__)
#define HUBWIRE_UNUSED __attribute__((unused))
#else
#define HUBWIRE_UNUSED
#endif
// A hook's constant, folded into the session's code (text.h).
#define HUBWIRE_HOOK(name) HUBWIRE_UNUSED HUBWIRE_FOLDED(name)

/// Declares a sketch's channels at file scope, outside any namespace (it defines
/// hubwire::sketchFeatures, features.h, and hubwire::sketchTable, channel.h); `var` is then what
/// begin() takes. After the device:
/// expose(), control(), action() and event() (dsl.h), mission() (mission.h), with their options, and what the sketch
/// expects of the hub: remote(), remoteAction() and remoteEvent() (remote.h).
///   HUBWIRE_CHANNELS(channels, "minimal", expose("blink_ms", blinkMs).writable(), event("button", button));
#define HUBWIRE_CHANNELS(var, deviceName, ...)                                                     \
  namespace hubwire_channels_##var {                                                               \
  using namespace ::hubwire::declare;                                                              \
  constexpr auto given = ::hubwire::declare::declared(deviceName, __VA_ARGS__);                    \
  /* the same as a type of a short name: the templates below are named after it, and a name */     \
  /* spelling 254 declarations in each of them cost g++ 12's debug info the square of the list */  \
  typedef decltype(given) Given;                                                                   \
  struct Sketch : Given {                                                                          \
    constexpr Sketch(const Given& g) : Given(g) {}                                                 \
  };                                                                                               \
  constexpr Sketch declared = Sketch(given);                                                       \
  inline void hubwire_collect_declared() {}                                                        \
  static_assert(::hubwire::declare::Reported<decltype(declared), &declared>::ok, "");                \
  inline void hubwire_collect_reported() {}                                                        \
  HUBWIRE_STEPS(TextStep)                                                                          \
  HUBWIRE_STEPS(HashStep)                                                                          \
  HUBWIRE_STEPS(DigestStep)                                                                        \
  /* the hub channels' values pass through the same value code (strings, structs) */               \
  constexpr uint16_t features =                                                                    \
      (uint16_t)(::hubwire::declare::featuresOf(declared.list) | ::hubwire::declare::featuresOf(declared.hub)); \
  typedef ::hubwire::declare::Stored<decltype(declared), &declared> Stored;                        \
  const Stored::JsonType json HUBWIRE_FLASH = Stored::json();                                      \
  const Stored::ExtrasType extras HUBWIRE_FLASH = Stored::ExtrasType();                            \
  const Stored::InfosType infos HUBWIRE_FLASH = Stored::infos(extras);                             \
  typedef decltype(declared) Decls;                                                                \
  constexpr uint16_t largeIn = ::hubwire::declare::largeInOf(declared.list);                       \
  constexpr bool large = (features & ::hubwire::kUsesLarge) != 0;                                  \
  namespace {                                                                                      \
  struct Tag {};                                                                                   \
  }                                                                                                \
  }                                                                                                \
  HUBWIRE_SKETCH_FEATURES(hubwire_channels_##var::features)                                        \
  template <>                                                                                      \
  const ::hubwire::HubTable* const ::HubwireHub<(hubwire_channels_##var::Decls::hubSize() > 0),    \
      ::HubwireHubTag<(hubwire_channels_##var::Decls::hubSize() > 0),                              \
                      hubwire_channels_##var::Tag>::type>::table HUBWIRE_HOOK("hub_table") =       \
      ::hubwire::declare::HubTableOf<hubwire_channels_##var::Decls, &hubwire_channels_##var::declared>:: \
          get<hubwire_channels_##var::Stored::InfosType, &hubwire_channels_##var::infos>();        \
  template <>                                                                                      \
  bool (*const ::HubwireHub<(hubwire_channels_##var::Decls::hubSize() > 0),                        \
      ::HubwireHubTag<(hubwire_channels_##var::Decls::hubSize() > 0),                              \
                      hubwire_channels_##var::Tag>::type>::dispatch)(::hubwire::Session&, bool)    \
      HUBWIRE_HOOK("hub_dispatch") =                                                               \
      ::hubwire::declare::HubTableOf<hubwire_channels_##var::Decls,                                \
                                     &hubwire_channels_##var::declared>::dispatch();               \
  HUBWIRE_LARGE_MEMBER(var, ::hubwire::Reassembly* const, state,                                     \
                       ::hubwire::declare::LargeStore<hubwire_channels_##var::largeIn>::get())      \
  HUBWIRE_LARGE_MEMBER(var, uint16_t const, capacity, hubwire_channels_##var::largeIn)              \
  HUBWIRE_LARGE_MEMBER(var, ::hubwire::FragmentReceiver const, receive, &::hubwire::fragmentReceived) \
  HUBWIRE_LARGE_MEMBER(var, ::hubwire::LargeSender const, send, &::hubwire::sendLarge)             \
  template <>                                                                                      \
  ::hubwire::HubLink* const ::HubwireHub<(hubwire_channels_##var::Decls::hubSize() > 0),           \
      ::HubwireHubTag<(hubwire_channels_##var::Decls::hubSize() > 0),                              \
                      hubwire_channels_##var::Tag>::type>::link HUBWIRE_HOOK("hub_link") =         \
      ::hubwire::declare::HubTableOf<hubwire_channels_##var::Decls,                                \
                                     &hubwire_channels_##var::declared>::link();                   \
  HUBWIRE_MISSIONS_HOOK(                                                                           \
  template <>                                                                                      \
  bool (*const ::HubwireMissions<                                                                  \
      ::hubwire::declare::anyMission(hubwire_channels_##var::declared.list),                       \
      ::HubwireHubTag<::hubwire::declare::anyMission(hubwire_channels_##var::declared.list),       \
                      hubwire_channels_##var::Tag>::type>::dispatch)(::hubwire::Session&, uint8_t) \
      HUBWIRE_HOOK("missions") = ::hubwire::declare::MissionHookOf<                                \
          ::hubwire::declare::anyMission(hubwire_channels_##var::declared.list)>::dispatch();)     \
  constexpr ::hubwire::ChannelTable var HUBWIRE_FLASH =                                            \
      ::hubwire::declare::table<decltype(hubwire_channels_##var::declared), &hubwire_channels_##var::declared>( \
          hubwire_channels_##var::json, hubwire_channels_##var::infos);                           \
  HUBWIRE_SKETCH_TABLE(var)

// The fragments' hooks (session/fragments.h): set for a sketch with a large value, else for a
// specialisation nothing reads. Type ends with const or *: clang would read `uint16_t ::X` as
// a name inside uint16_t.
#define HUBWIRE_LARGE_MEMBER(var, Type, member, value)                                             \
  template <>                                                                                      \
  Type ::HubwireLarge<hubwire_channels_##var::large,                                               \
                      ::HubwireHubTag<hubwire_channels_##var::large, hubwire_channels_##var::Tag>::type>::member \
      HUBWIRE_HOOK("large_" #member) = value;

// The sketch's features, for the session to test (features.h), its struct codec (wire/values.h),
// the missions' hook (session/missions.h) and its table (channel.h); none with
// HUBWIRE_ALL_FEATURES, whose programs (several tables) get the library's defaults built with it:
// every feature, missions reachable (session/mission_flag.cpp), no table of their own. Each is
// HUBWIRE_FOLDED (text.h): merged by identical-constant folding (a null codec with the library's
// null hooks), they were no longer folded into the code that reads them (Missions: +28 B flash,
// +6 B SRAM).
#if defined(HUBWIRE_ALL_FEATURES)
#define HUBWIRE_SKETCH_FEATURES(f)
#define HUBWIRE_MISSIONS_HOOK(...)
#define HUBWIRE_SKETCH_TABLE(var) static_assert(sizeof(var) != 0, "")
#else
#define HUBWIRE_SKETCH_FEATURES(f)                                                                 \
  const uint16_t hubwire::sketchFeatures HUBWIRE_FOLDED("sketch_features") = f;                      \
  const ::hubwire::StructCodec hubwire::sketchStructCodec HUBWIRE_FOLDED("sketch_codec") =          \
      ((f) & ::hubwire::kUsesStructs) ? &::hubwire::structCodec : nullptr;
#define HUBWIRE_MISSIONS_HOOK(...) __VA_ARGS__
// The sketch's table as a constant the session reads (channel.h), and the flash copy begin() takes.
#define HUBWIRE_SKETCH_TABLE(var)                                                                  \
  const ::hubwire::ChannelTable hubwire::sketchTable HUBWIRE_FOLDED("sketch_table") = var;         \
  const ::hubwire::ChannelTable* const hubwire::sketchTableAt HUBWIRE_FOLDED("sketch_table_at") = &var
#endif

#endif
