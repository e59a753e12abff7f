// The hub channels a sketch declares (remote.h), as the descriptor's "hub" list and as a flash
// table the session reads (session/hub_link.h).
//
// Paying only for what is used: the session's few hooks read hubTable(), a constant the library
// defines weakly as nullptr (session/hub_flag.cpp) and HUBWIRE_CHANNELS defines again, pointing at
// the sketch's table, only when the sketch declares hub channels (the explicit specialisations
// below). The hooks call the hub link through HubwireHub<true, void>::dispatch, which likewise only
// such a sketch defines: without hub channels the link-time optimiser folds the hooks away, so
// that nothing references the hub link's code or its RAM (what is left unresolved is a weak
// reference in code that is gone). (A program has at most one table with hub channels.)
#ifndef HUBWIRE_CHANNELS_HUB_TABLE_H
#define HUBWIRE_CHANNELS_HUB_TABLE_H

#include "../session/hub_link.h"
#include "tables.h"

namespace hubwire {

// The hub channels of the one table that declares them: hub id k is channels[k - 1]. owner is the
// device channel array of the same table (ChannelTable::channels), which tells its session.
class Session;
bool hubDispatch(Session& s, bool frame);  // session/hub_link.cpp

struct HubTable {
  const ChannelInfo* channels;
  const ChannelInfo* owner;
  uint8_t count;
};

}  // namespace hubwire

// In the global namespace, where HUBWIRE_CHANNELS can specialise it from any namespace: the
// <true, void> member is the one the session reads; a table without hub channels specialises
// <false, its own tag>, which nothing reads.
template <bool Declared, typename Tag>
struct HubwireHub {
  static const ::hubwire::HubTable* const table;
  static bool (*const dispatch)(::hubwire::Session& s, bool frame);
  static ::hubwire::HubLink* const link;  // the hub link, for missions to share its counter
};
template <>
const ::hubwire::HubTable* const HubwireHub<true, void>::table;
template <>
bool (*const HubwireHub<true, void>::dispatch)(::hubwire::Session& s, bool frame);
template <>
::hubwire::HubLink* const HubwireHub<true, void>::link;
template <bool Declared, typename Tag>
struct HubwireHubTag {
  typedef void type;
};
template <typename Tag>
struct HubwireHubTag<false, Tag> {
  typedef Tag type;
};

namespace hubwire {

// The sketch's hub table, or nullptr; folds to a constant where the sketch's table is known.
inline const HubTable* hubTable() { return HubwireHub<true, void>::table; }

namespace declare {

// ---- the flash table ----
// Owner: the sketch's own records (HUBWIRE_CHANNELS stores them, tables.h Stored), which tell the
// session that runs this table from another one in the same program.
template <typename D, const D* Decls, typename OwnerInfos, const OwnerInfos* Owner>
struct HubTableFlash {
  typedef typename HubSide<D, Decls>::Type HD;
  typedef Stored<HD, &HubSide<D, Decls>::value> S;
  static const typename S::ExtrasType extras;
  static const typename S::InfosType infos;
  static const HubTable value;
};
template <typename D, const D* Decls, typename OwnerInfos, const OwnerInfos* Owner>
const typename HubTableFlash<D, Decls, OwnerInfos, Owner>::S::ExtrasType
    HubTableFlash<D, Decls, OwnerInfos, Owner>::extras HUBWIRE_FLASH = typename S::ExtrasType();
template <typename D, const D* Decls, typename OwnerInfos, const OwnerInfos* Owner>
const typename HubTableFlash<D, Decls, OwnerInfos, Owner>::S::InfosType
    HubTableFlash<D, Decls, OwnerInfos, Owner>::infos HUBWIRE_FLASH = S::infos(extras);
template <typename D, const D* Decls, typename OwnerInfos, const OwnerInfos* Owner>
const HubTable HubTableFlash<D, Decls, OwnerInfos, Owner>::value HUBWIRE_FLASH = {
    infos.v, Owner->v, HubSide<D, Decls>::Type::size()};

template <typename D, const D* Decls, bool Hub = (D::hubSize() > 0)>
struct HubTableOf {
  template <typename OwnerInfos, const OwnerInfos* Owner>
  static constexpr const HubTable* get() { return nullptr; }
  static constexpr bool (*dispatch())(Session&, bool) { return nullptr; }
  static constexpr HubLink* link() { return nullptr; }
};
template <typename D, const D* Decls>
struct HubTableOf<D, Decls, true> {
  template <typename OwnerInfos, const OwnerInfos* Owner>
  static constexpr const HubTable* get() { return &HubTableFlash<D, Decls, OwnerInfos, Owner>::value; }
  static constexpr bool (*dispatch())(Session&, bool) { return &hubDispatch; }
  static constexpr HubLink* link() { return &hubLink; }
};


}  // namespace declare
}  // namespace hubwire

#endif
