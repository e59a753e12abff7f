// The compile-time JSON writer: the descriptor (docs/PROTOCOL.md 7) is written as pieces, each a
// literal prefix, one value (a number, an escaped string, access letters, a struct's fields) and a
// literal suffix, whose length and k-th character are constant expressions (tables.h lays them
// out in flash).
#ifndef HUBWIRE_CHANNELS_JSON_H
#define HUBWIRE_CHANNELS_JSON_H

#include <stddef.h>
#include <stdint.h>

#include "../wire/values.h"
#include "constexpr_text.h"
#include "layout.h"

namespace hubwire {
namespace declare {

// ---- JSON pieces: a literal prefix, one value, a literal suffix ----
enum PieceKind : uint8_t { kNone, kInteger, kFloat, kEscaped, kLiteral, kAccessLetters, kFields };

struct Piece {
  const char* pre;
  PieceKind kind;
  int64_t integer;  // kInteger; kAccessLetters: the access bits
  float real;       // kFloat
  const char* text;  // kEscaped, kLiteral, kFields (the layout text)
  const char* post;
};
constexpr Piece literal(const char* s) { return Piece{s, kNone, 0, 0, "", ""}; }
constexpr Piece integer(const char* pre, int64_t v) { return Piece{pre, kInteger, v, 0, "", ""}; }
constexpr Piece quoted(const char* pre, const char* s) { return Piece{pre, kEscaped, 0, 0, s, "\""}; }
constexpr Piece empty() { return literal(""); }

// Numbers: integers as themselves, floats (and doubles, as floats) through constexpr_text.h.
template <typename T>
constexpr Piece number(const char* pre, T v) {
  return integer(pre, (int64_t)v);
}
constexpr Piece number(const char* pre, float v) { return Piece{pre, kFloat, 0, v, "", ""}; }
constexpr Piece number(const char* pre, double v) { return Piece{pre, kFloat, 0, (float)v, "", ""}; }
constexpr Piece typeNamed(const char* pre, TypeCode t) { return Piece{pre, kLiteral, 0, 0, typeNameOf(t), "\""}; }

// Access letters in the descriptor's order: r w c e s m (the bits of Access, lowest first).
constexpr size_t accessLength(int64_t a) { return a ? (a & 1) + accessLength(a >> 1) : 0; }
constexpr char accessAt(int64_t a, size_t i, size_t bit = 0) {
  return (a & 1) ? (i == 0 ? "rwcesm"[bit] : accessAt(a >> 1, i - 1, bit + 1)) : accessAt(a >> 1, i, bit + 1);
}

// A value's length in two halves, numbers and texts, by kind: avr-g++ 5.4 paid for all six kinds'
// arms at every piece (32 channels with 60-character descriptions: 0.7 MB).
constexpr size_t numberValueLength(PieceKind kind, int64_t integer, float real) {
  return kind == kInteger ? cx::integerLength(integer) : kind == kFloat ? cx::floatLength(real) : accessLength(integer);
}
constexpr size_t textValueLength(PieceKind kind, const char* text) {
  return kind == kEscaped ? cx::escapedLength(text) : kind == kLiteral ? cx::length(text)
       : kind == kFields ? fieldsLength(text) : 0;
}
constexpr size_t valueLength(const Piece& p) {
  return p.kind == kInteger || p.kind == kFloat || p.kind == kAccessLetters ? numberValueLength(p.kind, p.integer, p.real)
                                                                            : textValueLength(p.kind, p.text);
}
constexpr char valueAt(const Piece& p, size_t i) {
  return p.kind == kInteger ? cx::integerAt(p.integer, i) : p.kind == kFloat ? cx::floatAt(p.real, i)
       : p.kind == kEscaped ? cx::escapedAt(p.text, i) : p.kind == kLiteral ? p.text[i]
       : p.kind == kAccessLetters ? accessAt(p.integer, i) : fieldsAt(p.text, i);
}
constexpr size_t pieceLength(const Piece& p) { return cx::length(p.pre) + valueLength(p) + cx::length(p.post); }
constexpr char pieceAt(const Piece& p, size_t i) {
  return i < cx::length(p.pre) ? p.pre[i]
       : i < cx::length(p.pre) + valueLength(p) ? valueAt(p, i - cx::length(p.pre))
                                                : p.post[i - cx::length(p.pre) - valueLength(p)];
}

}  // namespace declare
}  // namespace hubwire

#endif
