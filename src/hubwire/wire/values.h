// Channel value types and how they travel on the wire (docs/PROTOCOL.md 6).
#ifndef HUBWIRE_WIRE_VALUES_H
#define HUBWIRE_WIRE_VALUES_H

#include <stddef.h>
#include <stdint.h>

#include "../config.h"
#include "../text.h"

namespace hubwire {

enum TypeCode : uint8_t {
  kVoid = 0,
  kBool,
  kU8,
  kI8,
  kU16,
  kI16,
  kU32,
  kI32,
  kF32,
  kF64,
  kStr,     // bounded string: count = capacity
  kStruct,  // fields described by a layout, e.g. "ax:f32,gyro:i16[3]" (its compiled form below)
  kTypeCount
};

// A hubwire::List of scalars (channels/list.h): the element's code with this bit set; count is the
// capacity. Memory: a count byte, then the elements at their alignment.
const uint8_t kListFlag = 0x80;
constexpr TypeCode listOf(TypeCode t) { return (TypeCode)(t | kListFlag); }
constexpr bool isListCode(TypeCode t) { return (t & kListFlag) != 0; }
constexpr TypeCode elementOf(TypeCode t) { return (TypeCode)(t & ~kListFlag); }

// NAK error codes (docs/PROTOCOL.md 5).
enum ErrorCode : uint8_t {
  kOk = 0,
  kErrUnknownType = 1,
  kErrUnknownChannel = 2,
  kErrBadLength = 3,
  kErrOutOfRange = 4,
  kErrNotWritable = 5,
  kErrNotReadable = 6,
  kErrNotStreamable = 7,
  kErrBusy = 8,
  kErrBadOffset = 9,
  kErrNotLinked = 10,
  kErrBadValue = 11,
  kErrRejected = 12,
  kErrUnsupportedVersion = 13,
};

// Bytes of one scalar of this type (0 for void, str and struct).
uint8_t scalarSize(TypeCode t);
// The descriptor's name for the type ("f32", "str", ...).
Text typeName(TypeCode t);

// Maps C++ types to wire types at compile time.
template <typename T>
struct TypeOf {
  static const TypeCode code = (sizeof(T) == 1)   ? ((T)(-1) < (T)0 ? kI8 : kU8)
                               : (sizeof(T) == 2) ? ((T)(-1) < (T)0 ? kI16 : kU16)
                               : (sizeof(T) == 4) ? ((T)(-1) < (T)0 ? kI32 : kU32)
                                                  : kVoid;
};
template <>
struct TypeOf<bool> {
  static const TypeCode code = kBool;
};
template <>
struct TypeOf<float> {
  static const TypeCode code = kF32;
};
template <>
struct TypeOf<double> {
  static const TypeCode code = (sizeof(double) == 8) ? kF64 : kF32;
};

// Struct values are handled only through one function, called only where the sketch's features
// (features.h) include structs: a sketch that declares none links none of it. One function rather
// than a table of them, because AVR keeps such tables in RAM.
enum StructOp : uint8_t { kStructWireSize, kStructMemSize, kStructToWire, kStructCheck, kStructFromWire };
// One more op, reached only in sketches with large values (the codec folds it away in others):
// in = a StructWindow, out = wire bytes window.offset .. + len.
const StructOp kStructWireRange = (StructOp)5;
struct StructWindow {
  const void* mem;
  uint16_t offset;
};
// kStructToWire: in = memory, out = wire. kStructCheck: in = wire of the struct's wire size (check()
// judged the length already), its bools checked. kStructFromWire: in = wire,
// out = memory. layout is the compiled layout: per field its type code and element count, then
// kVoid ("ax:f32,gyro:i16[3]" is {kF32, 1, kI16, 3, kVoid}; channels/layout.h makes it).
uint16_t structCodec(StructOp op, const char* layout, const void* in, void* out, uint16_t len);
typedef uint16_t (*StructCodec)(StructOp op, const char* layout, const void* in, void* out, uint16_t len);
// &structCodec where the sketch declares a struct, else nullptr (HUBWIRE_CHANNELS defines it; with
// HUBWIRE_ALL_FEATURES, features.cpp): the value code calls the codec through it, so that a sketch
// without structs refers to none of it, and the linker drops it.
extern const StructCodec sketchStructCodec;

// A channel's value type as stored: scalar, fixed array (count > 0), string or struct.
struct ValueType {
  TypeCode code;
  uint8_t count;                // array elements (0 = a single scalar), or string capacity
  const char* layout;           // kStruct only: its fields, compiled (structCodec), in flash

  // Bytes of the value on the wire; for a string, its largest encoding (1 + capacity).
  uint16_t wireSize() const;
  // Bytes of the value in memory; 0 for a malformed struct layout.
  uint16_t memSize() const;
  // Copies a value from memory to its wire form; returns the wire length.
  uint16_t toWire(const void* mem, uint8_t* wire) const;
  // Checks a wire value (length, bools, string length). kOk or an error code.
  ErrorCode check(const uint8_t* wire, uint16_t len) const;
  // Copies a checked wire value into memory.
  void fromWire(const uint8_t* wire, uint16_t len, void* mem) const;
  // The wire length of the value in memory (a list's or string's actual length, else wireSize()).
  uint16_t wireLength(const void* mem) const;
  // Bytes offset .. offset+n-1 of the value's wire form, straight from memory (fragments:
  // no buffer holds the whole value).
  void wireRange(const void* mem, uint16_t offset, uint8_t* out, uint16_t n) const;
};

}  // namespace hubwire

#endif
