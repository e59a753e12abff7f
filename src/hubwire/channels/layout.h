// A struct channel's layout text, "ax:f32,gyro:i16[3]" (name:type[count] per field, in order),
// read while the sketch compiles: its size with the board's alignment (checked against sizeof the
// struct, tables.h), the descriptor's "f" list it stands for (json.h) and the compiled form the
// board's struct codec reads. Also the type names the descriptor and layouts spell.
#ifndef HUBWIRE_CHANNELS_LAYOUT_H
#define HUBWIRE_CHANNELS_LAYOUT_H

#include <stddef.h>
#include <stdint.h>

#include "../wire/values.h"
#include "constexpr_text.h"

namespace hubwire {
namespace declare {

constexpr const char* typeNameOf(TypeCode t) {
  return t == kBool ? "bool" : t == kU8 ? "u8" : t == kI8 ? "i8" : t == kU16 ? "u16" : t == kI16 ? "i16"
       : t == kU32 ? "u32" : t == kI32 ? "i32" : t == kF32 ? "f32" : t == kF64 ? "f64" : t == kStr ? "str"
       : t == kStruct ? "struct" : "void";
}
constexpr size_t scalarBytes(TypeCode t) { return t == kVoid || t > kF64 ? 0 : t <= kI8 ? 1 : t <= kI16 ? 2 : t <= kF32 ? 4 : 8; }

// A struct layout "ax:f32,gyro:i16[3]" becomes {"n":"ax","t":"f32"},{"n":"gyro","t":"i16","c":3}:
// each character of the layout stands for a short run of JSON.
constexpr bool fieldStart(const char* s, size_t j) { return j == 0 || s[j - 1] == ','; }
constexpr const char* fieldRun(const char* s, size_t j) {  // what goes before the character itself
  return s[j] == ':' ? "\",\"t\":\"" : s[j] == '[' ? "\",\"c\":" : s[j] == ']' ? "}" : s[j] == ',' ? (s[j - 1] == ']' ? "," : "\"},")
       : fieldStart(s, j) ? "{\"n\":\"" : "";
}
constexpr bool fieldKeepsChar(char c) { return c != ':' && c != '[' && c != ']' && c != ','; }
constexpr size_t fieldLength(const char* s, size_t j) { return cx::length(fieldRun(s, j)) + (fieldKeepsChar(s[j]) ? 1 : 0); }
constexpr const char* fieldsEnd(const char* s, size_t n) { return n && s[n - 1] == ']' ? "" : "\"}"; }
// Where the JSON of layout character j starts, each j once, and the j of JSON character i by a
// binary search (fieldsBefore(s, lo) <= i < fieldsBefore(s, hi)): linear in the layout's length
// where calls are remembered (constexpr_text.h), else a walk over the layout.
#if !HUBWIRE_CX_REMEMBERS
constexpr size_t fieldsLength(const char* s, size_t j = 0) {
  return s[j] ? fieldLength(s, j) + fieldsLength(s, j + 1) : cx::length(fieldsEnd(s, j));
}
constexpr char fieldsAt(const char* s, size_t i, size_t j = 0) {
  return !s[j] ? fieldsEnd(s, j)[i]
       : i < fieldLength(s, j) ? (i < cx::length(fieldRun(s, j)) ? fieldRun(s, j)[i] : s[j])
                               : fieldsAt(s, i - fieldLength(s, j), j + 1);
}
#else
constexpr size_t fieldsBefore(const char* s, size_t j) { return j == 0 ? 0 : fieldsBefore(s, j - 1) + fieldLength(s, j - 1); }
constexpr size_t fieldsLength(const char* s) {
  return fieldsBefore(s, cx::length(s)) + cx::length(fieldsEnd(s, cx::length(s)));
}
constexpr size_t fieldsSource(const char* s, size_t i, size_t lo, size_t hi) {
  return hi - lo == 1 ? lo
       : i < fieldsBefore(s, (lo + hi) / 2) ? fieldsSource(s, i, lo, (lo + hi) / 2) : fieldsSource(s, i, (lo + hi) / 2, hi);
}
constexpr char fieldCharAt(const char* s, size_t i, size_t j) {  // i-th character of layout character j's JSON
  return i < cx::length(fieldRun(s, j)) ? fieldRun(s, j)[i] : s[j];
}
constexpr char fieldsAt(const char* s, size_t i) {
  return i >= fieldsBefore(s, cx::length(s))
             ? fieldsEnd(s, cx::length(s))[i - fieldsBefore(s, cx::length(s))]
             : fieldCharAt(s, i - fieldsBefore(s, fieldsSource(s, i, 0, cx::length(s))), fieldsSource(s, i, 0, cx::length(s)));
}
#endif

// A layout's size in memory, with the alignment the board gives each field (so that it can be
// compared with sizeof the struct), or kBadLayout when the text is malformed.
const size_t kBadLayout = 0xFFFF;
constexpr bool typeNameAt(const char* s, size_t j, const char* n) {
  return *n == 0 ? (s[j] == 0 || s[j] == ',' || s[j] == '[') : s[j] == *n && typeNameAt(s, j + 1, n + 1);
}
constexpr TypeCode layoutTypeAt(const char* s, size_t j, uint8_t t = kBool) {
  return t > kF64 ? kVoid : typeNameAt(s, j, typeNameOf((TypeCode)t)) ? (TypeCode)t : layoutTypeAt(s, j, (uint8_t)(t + 1));
}
constexpr size_t colonAt(const char* s, size_t j) { return s[j] == 0 || s[j] == ':' || s[j] == ',' ? j : colonAt(s, j + 1); }
constexpr size_t digitsEnd(const char* s, size_t j) { return s[j] >= '0' && s[j] <= '9' ? digitsEnd(s, j + 1) : j; }
constexpr size_t numberIn(const char* s, size_t j, size_t end, size_t acc = 0) {
  return j == end ? acc : numberIn(s, j + 1, end, acc * 10 + (size_t)(s[j] - '0'));
}
constexpr size_t alignOfType(TypeCode t) {
  return t == kU16 || t == kI16 ? alignof(uint16_t) : t == kU32 || t == kI32 ? alignof(uint32_t)
       : t == kF32 ? alignof(float) : t == kF64 ? alignof(double) : 1;
}
constexpr size_t alignUp(size_t v, size_t a) { return (v + a - 1) / a * a; }
constexpr size_t maxOf(size_t a, size_t b) { return a > b ? a : b; }
// The field whose type name starts at t (after its colon) ends at e: a count "[n]" or nothing.
constexpr size_t countEnd(const char* s, size_t e) { return s[e] == '[' ? digitsEnd(s, e + 1) : e; }
constexpr bool countOk(const char* s, size_t e) {
  return s[e] != '[' || (s[countEnd(s, e)] == ']' && numberIn(s, e + 1, countEnd(s, e)) >= 1 &&
                         numberIn(s, e + 1, countEnd(s, e)) <= 255);
}
constexpr size_t countOf(const char* s, size_t e) { return s[e] == '[' ? numberIn(s, e + 1, countEnd(s, e)) : 1; }
constexpr size_t fieldEnd(const char* s, size_t e) { return s[e] == '[' ? countEnd(s, e) + 1 : e; }
constexpr size_t typeEnd(const char* s, size_t t) { return t + cx::length(typeNameOf(layoutTypeAt(s, t))); }
constexpr size_t layoutSizeAfter(const char* s, size_t next, size_t off, size_t maxAlign);
constexpr size_t layoutFieldSize(const char* s, size_t j, size_t off, size_t maxAlign) {
  return s[colonAt(s, j)] != ':' || colonAt(s, j) == j || layoutTypeAt(s, colonAt(s, j) + 1) == kVoid ||
                 !countOk(s, typeEnd(s, colonAt(s, j) + 1))
             ? kBadLayout
             : layoutSizeAfter(s, fieldEnd(s, typeEnd(s, colonAt(s, j) + 1)),
                               alignUp(off, alignOfType(layoutTypeAt(s, colonAt(s, j) + 1))) +
                                   scalarBytes(layoutTypeAt(s, colonAt(s, j) + 1)) * countOf(s, typeEnd(s, colonAt(s, j) + 1)),
                               maxOf(maxAlign, alignOfType(layoutTypeAt(s, colonAt(s, j) + 1))));
}
constexpr size_t layoutSizeAfter(const char* s, size_t next, size_t off, size_t maxAlign) {
  return s[next] == 0 ? alignUp(off, maxAlign)
       : s[next] == ',' && s[next + 1] != 0 ? layoutFieldSize(s, next + 1, off, maxAlign)
                                            : kBadLayout;
}
constexpr size_t layoutSize(const char* s) { return *s ? layoutFieldSize(s, 0, 0, 1) : kBadLayout; }

// A well-formed layout's size on the wire: its fields packed, without alignment.
constexpr size_t layoutWireAfter(const char* s, size_t next, size_t acc);
constexpr size_t layoutWireField(const char* s, size_t j, size_t acc) {
  return layoutWireAfter(s, fieldEnd(s, typeEnd(s, colonAt(s, j) + 1)),
                         acc + scalarBytes(layoutTypeAt(s, colonAt(s, j) + 1)) * countOf(s, typeEnd(s, colonAt(s, j) + 1)));
}
constexpr size_t layoutWireAfter(const char* s, size_t next, size_t acc) {
  return s[next] == ',' ? layoutWireField(s, next + 1, acc) : acc;
}
constexpr size_t layoutWireSize(const char* s) { return *s ? layoutWireField(s, 0, 0) : 0; }

// What the board keeps of a (well-formed) layout: per field its type code and element count (1 for
// a scalar), then kVoid, so that the struct codec reads two bytes a field instead of parsing text.
// "ax:f32,gyro:i16[3]" -> {kF32, 1, kI16, 3, kVoid}.
constexpr size_t layoutFields(const char* s, size_t j = 0) { return s[j] ? (s[j] == ',') + layoutFields(s, j + 1) : 1; }
constexpr size_t fieldAt(const char* s, size_t k, size_t j = 0) {  // where field k starts
  return k == 0 ? j : fieldAt(s, s[j] == ',' ? k - 1 : k, j + 1);
}
constexpr size_t compiledLayoutLength(const char* s) { return 2 * layoutFields(s) + 1; }
constexpr uint8_t compiledLayoutAt(const char* s, size_t i) {
  return i == 2 * layoutFields(s) ? (uint8_t)kVoid
       : i % 2 == 0             ? (uint8_t)layoutTypeAt(s, colonAt(s, fieldAt(s, i / 2)) + 1)
                                : (uint8_t)countOf(s, typeEnd(s, colonAt(s, fieldAt(s, i / 2)) + 1));
}

}  // namespace declare
}  // namespace hubwire

#endif
