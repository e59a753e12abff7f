// The fuzzers' binding of the core's seam (functions in each harness): the line the input feeds
// and a clock it advances. The session keeps a copy of its Port, so the Port only refers to them.
#ifndef HUBWIRE_FUZZ_PORT_H
#define HUBWIRE_FUZZ_PORT_H

#include <stddef.h>
#include <stdint.h>

#include <vector>

struct FuzzLine {
  std::vector<uint8_t> in, out;
  size_t pos = 0;
  size_t room = 4096;
  uint32_t now = 0;
};

namespace hubwire {

class Port {
 public:
  explicit Port(FuzzLine& l) : line(l) {}
  FuzzLine& line;
};

}  // namespace hubwire

#endif
