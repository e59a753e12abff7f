// The library's answer to "where is the reassembly buffer": nowhere. A sketch that declares a
// large writable value or argument defines these again (HUBWIRE_CHANNELS, session/fragments.h).
// Alone in this file, so that no other code sees the weak value as a constant.
#include "fragments.h"
#include "../text.h"

template <>
__attribute__((weak))::hubwire::Reassembly* const HubwireLarge<true, void>::state HUBWIRE_FOLDED("large_state") = nullptr;
template <>
__attribute__((weak)) const uint16_t HubwireLarge<true, void>::capacity HUBWIRE_FOLDED("large_capacity") = 0;
template <>
__attribute__((weak)) const ::hubwire::FragmentReceiver HubwireLarge<true, void>::receive HUBWIRE_FOLDED("large_receive") = nullptr;
template <>
__attribute__((weak)) const ::hubwire::LargeSender HubwireLarge<true, void>::send HUBWIRE_FOLDED("large_send") = nullptr;
