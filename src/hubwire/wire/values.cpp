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

uint16_t alignUp(uint16_t v, uint8_t a) { return (uint16_t)((v + a - 1) / a * a); }

}  // namespace

uint8_t scalarSize(TypeCode t) {  // arithmetic, not a switch: AVR keeps switch tables in RAM
  if (t == kVoid || t > kF64) return 0;
  return t <= kI8 ? 1 : t <= kI16 ? 2 : t <= kF32 ? 4 : 8;
}


Text typeName(TypeCode t) {
  if (t >= kTypeCount) t = kVoid;
  return flashText(kTypeNames + t * kNameStride);
}

bool LayoutReader::next(LayoutField& f) {
  if (!ok || text_.at(pos_) == 0) return false;
  f.nameStart = pos_;
  while (text_.at(pos_) && text_.at(pos_) != ':') ++pos_;
  f.nameLen = (uint16_t)(pos_ - f.nameStart);
  if (text_.at(pos_) != ':' || f.nameLen == 0) return ok = false;
  ++pos_;
  // Match the type name against the scalar names.
  f.code = kVoid;
  for (uint8_t t = kBool; t <= kF64; ++t) {
    Text name = typeName((TypeCode)t);
    uint8_t k = 0;
    while (name.at(k) && name.at(k) == text_.at(pos_ + k)) ++k;
    char after = text_.at(pos_ + k);
    if (name.at(k) == 0 && (after == 0 || after == ',' || after == '[')) {
      f.code = (TypeCode)t;
      pos_ = (uint16_t)(pos_ + k);
      break;
    }
  }
  if (f.code == kVoid) return ok = false;
  f.count = 0;
  if (text_.at(pos_) == '[') {
    ++pos_;
    uint16_t n = 0;
    while (text_.at(pos_) >= '0' && text_.at(pos_) <= '9') n = (uint16_t)(n * 10 + (text_.at(pos_++) - '0'));
    if (text_.at(pos_) != ']' || n == 0 || n > 255) return ok = false;
    ++pos_;
    f.count = (uint8_t)n;
  }
  if (text_.at(pos_) == ',') {
    ++pos_;
    if (text_.at(pos_) == 0) return ok = false;
  } else if (text_.at(pos_) != 0) {
    return ok = false;
  }
  return true;
}

namespace {

uint16_t fieldBytes(const LayoutField& f) { return (uint16_t)(scalarSize(f.code) * (f.count ? f.count : 1)); }

uint16_t structWireSize(Text layout) {
  uint16_t n = 0;
  LayoutReader r(layout);
  LayoutField f;
  while (r.next(f)) n = (uint16_t)(n + fieldBytes(f));
  return n;
}

uint16_t structMemSize(Text layout) {
  uint16_t n = 0;
  uint8_t maxAlign = 1;
  LayoutReader r(layout);
  LayoutField f;
  while (r.next(f)) {
    uint8_t a = alignOf(f.code);
    if (a > maxAlign) maxAlign = a;
    n = (uint16_t)(alignUp(n, a) + fieldBytes(f));
  }
  return r.ok ? alignUp(n, maxAlign) : 0;  // 0 also for an empty layout
}

// Copies field by field between the packed wire form and the aligned memory form.
uint16_t structCopy(Text layout, uint8_t* mem, uint8_t* wire, bool toWire) {
  uint16_t memOff = 0, wireOff = 0;
  LayoutReader r(layout);
  LayoutField f;
  while (r.next(f)) {
    uint16_t n = fieldBytes(f);
    memOff = alignUp(memOff, alignOf(f.code));
    if (toWire) {
      memcpy(wire + wireOff, mem + memOff, n);
    } else {
      memcpy(mem + memOff, wire + wireOff, n);
    }
    memOff = (uint16_t)(memOff + n);
    wireOff = (uint16_t)(wireOff + n);
  }
  return wireOff;
}

uint16_t structToWire(Text layout, const void* mem, uint8_t* wire) {
  return structCopy(layout, (uint8_t*)mem, wire, true);
}

void structFromWire(Text layout, const uint8_t* wire, void* mem) {
  structCopy(layout, (uint8_t*)mem, (uint8_t*)wire, false);
}

bool boolsValid(TypeCode t, const uint8_t* p, uint16_t n) {
  if (t != kBool) return true;
  for (uint16_t i = 0; i < n; ++i)
    if (p[i] > 1) return false;
  return true;
}

ErrorCode structCheck(Text layout, const uint8_t* wire, uint16_t len) {
  if (len != structWireSize(layout)) return kErrBadLength;
  uint16_t off = 0;
  LayoutReader r(layout);
  LayoutField f;
  while (r.next(f)) {
    uint16_t n = fieldBytes(f);
    if (!boolsValid(f.code, wire + off, n)) return kErrBadValue;
    off = (uint16_t)(off + n);
  }
  return kOk;
}

// Bytes [lo, lo + n) of a struct's wire form, field by field from its aligned memory form.
uint16_t structWireRange(Text layout, const StructWindow* w, uint8_t* out, uint16_t n) {
  const uint8_t* mem = (const uint8_t*)w->mem;
  uint16_t memOff = 0, wireOff = 0, lo = w->offset, hi = (uint16_t)(w->offset + n);
  LayoutReader r(layout);
  LayoutField f;
  while (r.next(f) && wireOff < hi) {
    // (fieldBytes() and alignUp() spelled out: one more caller would change how the compiler
    // inlines them into the struct codec of every sketch)
    uint16_t k = (uint16_t)(scalarSize(f.code) * (f.count ? f.count : 1));
    uint8_t align = alignOf(f.code);
    memOff = (uint16_t)((memOff + align - 1) / align * align);
    uint16_t a = wireOff > lo ? wireOff : lo, b = wireOff + k < hi ? (uint16_t)(wireOff + k) : hi;
    if (a < b) memcpy(out + (a - lo), mem + memOff + (a - wireOff), (size_t)(b - a));
    memOff = (uint16_t)(memOff + k);
    wireOff = (uint16_t)(wireOff + k);
  }
  return n;
}

// A list's elements start at their own alignment after the count byte.
uint8_t listItems(TypeCode code) { return alignOf(elementOf(code)); }

}  // namespace

uint16_t structCodec(StructOp op, Text layout, const void* in, void* out, uint16_t len) {
  if (uses(kUsesLarge) && op == kStructWireRange)
    return structWireRange(layout, (const StructWindow*)in, (uint8_t*)out, len);
  switch (op) {
    case kStructWireSize:
      return structWireSize(layout);
    case kStructMemSize:
      return structMemSize(layout);
    case kStructToWire:
      return structToWire(layout, in, (uint8_t*)out);
    case kStructCheck:
      return structCheck(layout, (const uint8_t*)in, len);
    case kStructFromWire:
      structFromWire(layout, (const uint8_t*)in, out);
      return 0;
  }
  return 0;
}

uint16_t ValueType::wireSize() const {
  if (uses(kUsesLists) && isListCode(code)) return (uint16_t)(1 + count * scalarSize(elementOf(code)));
  if (uses(kUsesStrings) && code == kStr) return (uint16_t)(1 + count);
  if (uses(kUsesStructs) && code == kStruct) return structs(kStructWireSize, layout, nullptr, nullptr, 0);
  return (uint16_t)(scalarSize(code) * (count ? count : 1));
}

uint16_t ValueType::memSize() const {
  if (uses(kUsesLists) && isListCode(code)) {
    uint8_t a = listItems(code);
    return alignUp((uint16_t)(a + count * scalarSize(elementOf(code))), a);
  }
  if (uses(kUsesStrings) && code == kStr) return (uint16_t)(count + 1);  // NUL-terminated char array
  if (uses(kUsesStructs) && code == kStruct) return structs(kStructMemSize, layout, nullptr, nullptr, 0);
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
  if (uses(kUsesStructs) && code == kStruct) return structs(kStructToWire, layout, mem, wire, 0);
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
  if (uses(kUsesStructs) && code == kStruct) return (ErrorCode)structs(kStructCheck, layout, wire, nullptr, len);
  if (len != wireSize()) return kErrBadLength;
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
  } else if (uses(kUsesStructs) && code == kStruct) {
    structs(kStructFromWire, layout, wire, mem, len);
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
  if (uses(kUsesStructs) && code == kStruct) {
    StructWindow w = {mem, offset};
    structs(kStructWireRange, layout, &w, out, n);
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
