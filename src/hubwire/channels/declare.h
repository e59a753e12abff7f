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

// One job a header: the declarations a sketch writes (dsl.h), the JSON they become (json.h; a
// struct's layout: layout.h), and the flash tables with their checks (tables.h).
#include "dsl.h"
#include "tables.h"

/// Declares a sketch's channels at file scope, outside any namespace (it defines
/// hubwire::sketchFeatures, features.h); `var` is then what begin() takes. After the device:
/// expose(), control(), action() and event() (dsl.h), with their options.
///   HUBWIRE_CHANNELS(channels, "minimal", expose("blink_ms", blinkMs).writable(), event("button", button));
#define HUBWIRE_CHANNELS(var, deviceName, ...)                                                     \
  namespace hubwire_channels_##var {                                                               \
  using namespace ::hubwire::declare;                                                              \
  constexpr auto declared = ::hubwire::declare::declared(deviceName, __VA_ARGS__);                 \
  constexpr uint16_t features = ::hubwire::declare::featuresOf(declared.list);                     \
  typedef ::hubwire::declare::Stored<decltype(declared), &declared> Stored;                        \
  const Stored::JsonType json HUBWIRE_FLASH = Stored::json();                                      \
  const Stored::ExtrasType extras HUBWIRE_FLASH = Stored::ExtrasType();                            \
  const Stored::InfosType infos HUBWIRE_FLASH = Stored::infos(extras);                             \
  }                                                                                                \
  HUBWIRE_SKETCH_FEATURES(hubwire_channels_##var::features)                                        \
  constexpr ::hubwire::ChannelTable var HUBWIRE_FLASH =                                            \
      ::hubwire::declare::table<decltype(hubwire_channels_##var::declared), &hubwire_channels_##var::declared>( \
          hubwire_channels_##var::json, hubwire_channels_##var::infos)

// The sketch's features, for the session to test (features.h); none with HUBWIRE_ALL_FEATURES.
#if defined(HUBWIRE_ALL_FEATURES)
#define HUBWIRE_SKETCH_FEATURES(f)
#else
#define HUBWIRE_SKETCH_FEATURES(f) const uint16_t hubwire::sketchFeatures HUBWIRE_RODATA = f;
#endif

#endif
