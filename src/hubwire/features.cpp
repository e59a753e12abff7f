// Every feature on, for a program whose HUBWIRE_CHANNELS defines no sketchFeatures
// (HUBWIRE_ALL_FEATURES): weak, so the one HUBWIRE_CHANNELS defines takes its place.
#include "features.h"

#include "wire/values.h"

namespace hubwire {

extern const uint16_t sketchFeatures __attribute__((weak));
const uint16_t sketchFeatures = kAllFeatures;
extern const StructCodec sketchStructCodec __attribute__((weak));
const StructCodec sketchStructCodec = &structCodec;

}  // namespace hubwire
