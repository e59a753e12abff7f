// Which features a sketch's declarations use, as a constant the whole program sees: the session
// tests it, and with link-time optimisation (the Arduino builds use -flto) the compiler folds
// every path of a feature the sketch does not use away. HUBWIRE_CHANNELS defines it (channels/declare.h).
//
// A program with more than one HUBWIRE_CHANNELS (several hubs, or tests) defines
// HUBWIRE_ALL_FEATURES for every file: the macro then defines nothing and the library's default,
// every feature on, holds (features.cpp). Otherwise the linker reports hubwire::sketchFeatures
// defined twice.
#ifndef HUBWIRE_CHANNELS_FEATURES_H
#define HUBWIRE_CHANNELS_FEATURES_H

#include <stdint.h>

#include "config.h"

namespace hubwire {

const uint16_t kUsesStreams = 1;  // a streamable() variable: subscriptions and samples
const uint16_t kUsesFailsafes = 2;  // failsafe(): applied when the link is lost
const uint16_t kUsesStrings = 4;  // a char[] channel
const uint16_t kUsesStructs = 8;  // a struct channel
const uint16_t kUsesCalls = 16;  // control() or action(): a function called with the hub's value
const uint16_t kUsesReturns = 32;  // an action() that returns a value
const uint16_t kUsesEvents = 64;  // event(): the queue, its retries and ACKs
const uint16_t kUsesRanges = 128;  // range(): writes checked against it
const uint16_t kUsesWrites = 256;  // writable() variables (and onChange())
const uint16_t kUsesReads = 512;  // readable variables: requests answered with their value
const uint16_t kUsesLists = 1024;  // a hubwire::List<T, N> value: the variable-length codec
const uint16_t kUsesLarge = 2048;  // a value whose message may not fit one frame: fragments
const uint16_t kUsesMissions = 4096;  // mission(): starts, cancels and the M updates (session/missions.h)
const uint16_t kUsesControlFailsafes = 8192;  // failsafe() on a control: called with it when the link is lost
// A value whose answer or sample may not fit the 16 bytes of payload every hub accepts: only then
// is its length checked against the hub's limit.
const uint16_t kUsesWide = 16384;
const uint16_t kAllFeatures = 0x7FFF;

extern const uint16_t sketchFeatures;

/// Does the sketch use any of the features f? A constant with link-time optimisation.
///   if (!uses(kUsesStreams)) return;
HUBWIRE_ALWAYS_INLINE bool uses(uint16_t f) { return (sketchFeatures & f) != 0; }

}  // namespace hubwire

#endif
