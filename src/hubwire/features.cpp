// Every feature on, and no table of the sketch's own, for a program whose HUBWIRE_CHANNELS
// defines no sketchFeatures (HUBWIRE_ALL_FEATURES): weak, so the one HUBWIRE_CHANNELS defines
// takes its place.
#include "features.h"

#include "channels/channel.h"
#include "wire/values.h"

namespace hubwire {

extern const uint16_t sketchFeatures __attribute__((weak));
const uint16_t sketchFeatures = kAllFeatures;
extern const StructCodec sketchStructCodec __attribute__((weak));
const StructCodec sketchStructCodec = &structCodec;
extern const ChannelTable sketchTable __attribute__((weak));
const ChannelTable sketchTable = {nullptr, 0, 0, nullptr, 0};
extern const ChannelTable* const sketchTableAt __attribute__((weak));
const ChannelTable* const sketchTableAt = nullptr;

}  // namespace hubwire
