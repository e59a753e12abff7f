#include "values.h"

#include <string.h>

#include "../features.h"

namespace hubwire {

namespace {

// One flash string holding every type name, 7 bytes apart, so the table costs no pointers.
const char kTypeNames[] HUBWIRE_FLASH =
    "void\0\0\0bool\0\0\0u8\0\0\0\0\0i8\0\0\0\0\0u16\0\0\0\0i16\0\0\0\0u32\0\0\0\0i32\0\0\0\0f32\0\0\0\0f64\0\0\0\0"
    "str\0\0\0\0struct";
const uint8_t kNameStride = 7;

uint8_t alignOf(TypeCode t) {
  switch (t) {
    case kU16:
    case kI16:
      return (uint8_t)alignof(uint16_t);
    case kU32:
    case kI32:
      return (uint8_t)alignof(uint32_t);
    case kF32:
      return (uint8_t)alignof(float);
    case kF64:
      return (uint8_t)alignof(double);
    default:
      return 1;
  }
}

// Where no scalar needs alignment (AVR), a struct's memory form is its wire form: its values are
// copied as they are, and the codec walks the fields only for sizes and checks.
const bool kPackedStructs = alignof(uint16_t) == 1 && alignof(uint32_t) == 1 && alignof(float) == 1 && alignof(double) == 1;

uint16_t alignUp(uint16_t v, uint8_t a) { return (uint16_t)((v + a - 1) / a * a); }

bool boolsValid(TypeCode t, const uint8_t* p, uint16_t n) {
  if (t != kBool) return true;
  for (uint16_t i = 0; i < n; ++i)
    if (p[i] > 1) return false;
  return true;
}

// A list's elements start at their own alignment after the count byte.
uint8_t listItems(TypeCode code) { return alignOf(elementOf(code)); }

}  // namespace

// Bytes per scalar type, void .. f64: a flash table read takes less code than comparisons.
const uint8_t kScalarSizes[] HUBWIRE_FLASH = {0, 1, 1, 1, 2, 2, 4, 4, 4, 8};

uint8_t scalarSize(TypeCode t) {
  if (t > kF64) return 0;
  return flashRead(&kScalarSizes[t]);
}


Text typeName(TypeCode t) {
  if (t >= kTypeCount) t = kVoid;
  return flashText(kTypeNames + t * kNameStride);
}

// One walk over the fields serves every operation: the wire form is packed, the memory form has
// each field at its alignment. Ifs rather than a switch: AVR keeps switch tables in RAM.
uint16_t structCodec(StructOp op, const char* compiled, const void* in, void* out, uint16_t len) {
  Text layout = flashText(compiled);
  const uint8_t* from = (const uint8_t*)in;
  uint8_t* to = (uint8_t*)out;
  uint16_t memOff = 0, wireOff = 0, lo = 0;
  uint8_t maxAlign = 1;
  // kStructWireRange (large values only, so folded away for every other sketch): in = a window
  // over the memory form, out = its wire bytes lo .. lo + len.
  bool window = uses(kUsesLarge) && op == kStructWireRange;
  if (window) {
    const StructWindow* w = (const StructWindow*)in;
    from = (const uint8_t*)w->mem;
    lo = w->offset;
  }
  for (uint16_t i = 0;; i = (uint16_t)(i + 2)) {
    TypeCode code = (TypeCode)layout.at(i);
    if (code == kVoid) break;
    uint16_t n = (uint16_t)(scalarSize(code) * (uint8_t)layout.at((uint16_t)(i + 1)));
    uint8_t a = alignOf(code);
    if (a > maxAlign) maxAlign = a;
    memOff = kPackedStructs ? wireOff : alignUp(memOff, a);
    if (!kPackedStructs && op == kStructToWire) memcpy(to + wireOff, from + memOff, n);
    if (!kPackedStructs && op == kStructFromWire) memcpy(to + memOff, from + wireOff, n);
    if (op == kStructCheck && !boolsValid(code, from + wireOff, n)) return kErrBadValue;
    if (!kPackedStructs && window) {  // the part of this field inside the window
      uint16_t first = wireOff > lo ? wireOff : lo, end = (uint16_t)(lo + len);
      if (wireOff + n < end) end = (uint16_t)(wireOff + n);
      if (first < end) memcpy(to + (first - lo), from + memOff + (first - wireOff), (size_t)(end - first));
    }
    memOff = (uint16_t)(memOff + n);
    wireOff = (uint16_t)(wireOff + n);
  }
  if (op == kStructMemSize) return alignUp(memOff, maxAlign);
  if (op == kStructCheck) return kOk;
  return wireOff;  // kStructWireSize, kStructToWire; ignored for kStructFromWire, kStructWireRange
}

uint16_t ValueType::wireSize() const {
  if (uses(kUsesLists) && isListCode(code)) return (uint16_t)(1 + count * scalarSize(elementOf(code)));
  if (uses(kUsesStrings) && code == kStr) return (uint16_t)(1 + count);
  if (uses(kUsesStructs) && code == kStruct) return sketchStructCodec(kStructWireSize, layout, nullptr, nullptr, 0);
  uint8_t n = count ? count : 1;
  return (uint16_t)(scalarSize(code) * n);  // two bytes: one 8x8 multiply on AVR
}

uint16_t ValueType::memSize() const {
  if (uses(kUsesLists) && isListCode(code)) {
    uint8_t a = listItems(code);
    return alignUp((uint16_t)(a + count * scalarSize(elementOf(code))), a);
  }
  if (uses(kUsesStrings) && code == kStr) return (uint16_t)(count + 1);  // NUL-terminated char array
  if (uses(kUsesStructs) && code == kStruct) return sketchStructCodec(kStructMemSize, layout, nullptr, nullptr, 0);
  return wireSize();
}

uint16_t ValueType::toWire(const void* mem, uint8_t* wire) const {
  const uint8_t* m = (const uint8_t*)mem;
  if (uses(kUsesLists) && isListCode(code)) {
    uint16_t n = wireLength(mem);
    wire[0] = m[0] < count ? m[0] : count;
    memcpy(wire + 1, m + listItems(code), n - 1u);
    return n;
  }
  if (uses(kUsesStrings) && code == kStr) {
    uint8_t n = 0;
    while (n < count && m[n]) ++n;
    wire[0] = n;
    memcpy(wire + 1, m, n);
    return (uint16_t)(n + 1);
  }
  if (uses(kUsesStructs) && code == kStruct && !kPackedStructs) return sketchStructCodec(kStructToWire, layout, mem, wire, 0);
  uint16_t n = wireSize();
  memcpy(wire, m, n);
  return n;
}

ErrorCode ValueType::check(const uint8_t* wire, uint16_t len) const {
  if (uses(kUsesLists) && isListCode(code)) {  // as a string: the count first, then the length it implies
    if (len < 1) return kErrBadLength;
    if (wire[0] > count) return kErrBadValue;
    if (len != 1u + wire[0] * scalarSize(elementOf(code))) return kErrBadLength;
    return boolsValid(elementOf(code), wire + 1, (uint16_t)(len - 1)) ? kOk : kErrBadValue;
  }
  if (uses(kUsesStrings) && code == kStr) {  // the length byte is judged first, then the payload against it
    if (len < 1) return kErrBadLength;
    if (wire[0] > count) return kErrBadValue;
    return len == 1u + wire[0] ? kOk : kErrBadLength;
  }
  if (len != wireSize()) return kErrBadLength;  // a value of the wrong length, whatever its bytes
  if (uses(kUsesStructs) && code == kStruct) return (ErrorCode)sketchStructCodec(kStructCheck, layout, wire, nullptr, len);
  return boolsValid(code, wire, len) ? kOk : kErrBadValue;
}

void ValueType::fromWire(const uint8_t* wire, uint16_t len, void* mem) const {
  uint8_t* m = (uint8_t*)mem;
  if (uses(kUsesLists) && isListCode(code)) {
    m[0] = wire[0];
    memcpy(m + listItems(code), wire + 1, len - 1u);
    return;
  }
  if (uses(kUsesStrings) && code == kStr) {
    memcpy(m, wire + 1, wire[0]);
    m[wire[0]] = 0;
  } else if (uses(kUsesStructs) && code == kStruct && !kPackedStructs) {
    sketchStructCodec(kStructFromWire, layout, wire, mem, len);
  } else {
    memcpy(m, wire, len);
  }
}

uint16_t ValueType::wireLength(const void* mem) const {
  const uint8_t* m = (const uint8_t*)mem;
  if (uses(kUsesLists) && isListCode(code)) {
    uint8_t n = m[0] < count ? m[0] : count;  // a sketch that overfilled count sends what fits
    return (uint16_t)(1 + n * scalarSize(elementOf(code)));
  }
  if (uses(kUsesStrings) && code == kStr) {
    uint8_t n = 0;
    while (n < count && m[n]) ++n;
    return (uint16_t)(n + 1);
  }
  return wireSize();
}

void ValueType::wireRange(const void* mem, uint16_t offset, uint8_t* out, uint16_t n) const {
  const uint8_t* m = (const uint8_t*)mem;
  if (n == 0) return;
  if (uses(kUsesStructs) && code == kStruct && !kPackedStructs) {
    StructWindow w = {mem, offset};
    sketchStructCodec(kStructWireRange, layout, &w, out, n);
    return;
  }
  bool counted = (uses(kUsesLists) && isListCode(code)) || (uses(kUsesStrings) && code == kStr);
  if (!counted) {
    memcpy(out, m + offset, n);
    return;
  }
  if (offset == 0) {  // the count byte, then the elements
    *out++ = code == kStr ? (uint8_t)(wireLength(mem) - 1) : m[0] < count ? m[0] : count;
    --n;
    offset = 1;
  }
  uint8_t items = code == kStr ? 0 : listItems(code);
  memcpy(out, m + items + offset - 1, n);
}

}  // namespace hubwire
