// Tight2: the descriptor JSON generated on the board from run-time declarations, replayed from the
// sketch's declarations function like the current library (src/hubwire/session/device.h).
#ifndef TIGHT_DECL_H
#define TIGHT_DECL_H

#include "tight.h"

enum TwType : uint8_t { TWT_VOID, TWT_BOOL, TWT_U8, TWT_I8, TWT_U16, TWT_I16, TWT_U32, TWT_I32, TWT_F32 };
template <typename T> struct TwTypeOf;
template <> struct TwTypeOf<bool> { static const TwType code = TWT_BOOL; };
template <> struct TwTypeOf<uint8_t> { static const TwType code = TWT_U8; };
template <> struct TwTypeOf<int8_t> { static const TwType code = TWT_I8; };
template <> struct TwTypeOf<uint16_t> { static const TwType code = TWT_U16; };
template <> struct TwTypeOf<int16_t> { static const TwType code = TWT_I16; };
template <> struct TwTypeOf<uint32_t> { static const TwType code = TWT_U32; };
template <> struct TwTypeOf<int32_t> { static const TwType code = TWT_I32; };

template <typename T> struct TwEvent { uint8_t id = 0; };

class TwHub {
 public:
  template <typename T> TwHub& expose(const __FlashStringHelper* n, T&) { return declare(n, TwTypeOf<T>::code, TW_R); }
  template <typename T> TwHub& control(const __FlashStringHelper* n, void (*)(T)) {
    return declare(n, TwTypeOf<T>::code, TW_W);
  }
  template <typename T> TwHub& event(const __FlashStringHelper* n, TwEvent<T>& ev) {
    declare(n, TwTypeOf<T>::code, TW_E);
    ev.id = id_;
    return *this;
  }
  TwHub& writable() { return access_ |= TW_W, *this; }
  TwHub& streamable() { return access_ |= TW_S, *this; }
  TwHub& range(int32_t lo, int32_t hi) { return min_ = lo, max_ = hi, hasRange_ = true, *this; }
  TwHub& unit(const __FlashStringHelper* u) { return unit_ = u, *this; }

  void begin(const __FlashStringHelper* name, void (*decls)()) {
    name_ = name;
    decls_ = decls;
    twBegin();
  }
  void update() { twUpdate(); }
  template <typename T> bool emit(const TwEvent<T>& ev, T v) { return twEmit(ev.id, &v, sizeof(T)); }

  void describe();  // writes the whole descriptor through the window

 private:
  TwHub& declare(const __FlashStringHelper* n, TwType t, uint8_t access);
  void finish();

  const __FlashStringHelper* name_;
  void (*decls_)();
  const __FlashStringHelper* chName_;
  const __FlashStringHelper* unit_;
  int32_t min_, max_;
  uint8_t id_;
  TwType type_;
  uint8_t access_;
  bool hasRange_, pending_;
};

extern TwHub hub;

#endif
