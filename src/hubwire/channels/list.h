// hubwire::List<T, N>: a variable-length array of up to N scalars, carried with its length (one
// count byte, then the elements: docs/PROTOCOL.md 6). Declared like any value:
//   hubwire::List<int16_t, 8> path;
//   HUBWIRE_CHANNELS(channels, "arm", expose("path", path).writable());
#ifndef HUBWIRE_CHANNELS_LIST_H
#define HUBWIRE_CHANNELS_LIST_H

#include <stddef.h>
#include <stdint.h>

namespace hubwire {

// An aggregate, so a global List starts empty (count 0) and costs exactly its bytes.
template <typename T, size_t N>
struct List {
  static_assert(N >= 1 && N <= 255, "a List holds 1..255 elements");
  uint8_t count;  // elements in use; the codec reads items[0 .. count-1]
  T items[N];

  /// Elements in use.
  ///   for (uint8_t i = 0; i < path.size(); ++i) go(path[i]);
  uint8_t size() const { return count; }
  /// The most it holds (N).
  static constexpr uint8_t capacity() { return (uint8_t)N; }
  T& operator[](uint8_t i) { return items[i]; }
  const T& operator[](uint8_t i) const { return items[i]; }
  /// Appends v; false when full.
  ///   if (!path.push(12)) { /* full */ }
  bool push(const T& v) {
    if (count >= N) return false;
    items[count++] = v;
    return true;
  }
  /// Empties it.
  void clear() { count = 0; }
};

}  // namespace hubwire

#endif
