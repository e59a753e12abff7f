// The library's answer to "does the sketch declare a mission": no. A sketch that declares one
// defines this constant again (HUBWIRE_CHANNELS, channels/declare.h), and the linker takes its
// definition over this weak one. Kept alone in this file: within one file the compiler would fold
// the weak value into the code that reads it. A program built with HUBWIRE_ALL_FEATURES (several
// tables, none defining it) gets the run time, as it gets every other feature (features.cpp).
#include "missions.h"
#include "../text.h"

template <>
__attribute__((weak)) bool (*const HubwireMissions<true, void>::dispatch)(::hubwire::Session&, uint8_t)
    HUBWIRE_FOLDED("missions") =
#if defined(HUBWIRE_ALL_FEATURES)
    &::hubwire::missionDispatch;
#else
    nullptr;
#endif
