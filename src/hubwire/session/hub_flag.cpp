// The library's answer to "which table declares hub channels": none. A sketch that declares some
// defines this constant again (HUBWIRE_CHANNELS, channels/hub_table.h), and the linker takes its
// definition over this weak one. Kept alone in this file: within one file the compiler would fold
// the weak value into the code that reads it.
#include "../channels/hub_table.h"
#include "../text.h"

template <>
__attribute__((weak)) const ::hubwire::HubTable* const HubwireHub<true, void>::table HUBWIRE_FOLDED("hub_table") = nullptr;
template <>
__attribute__((weak)) bool (*const HubwireHub<true, void>::dispatch)(::hubwire::Session&, bool)
    HUBWIRE_FOLDED("hub_dispatch") = nullptr;
template <>
__attribute__((weak))::hubwire::HubLink* const HubwireHub<true, void>::link HUBWIRE_FOLDED("hub_link") = nullptr;
