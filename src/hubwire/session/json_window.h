// Writes the descriptor JSON as a stream of characters without keeping it anywhere: it counts every
// character, hashes it, and copies only those that fall in the requested window into a buffer.
// This is how a 1 KB descriptor is served in chunks from a device with 2 KB of RAM.
#ifndef HUBWIRE_SESSION_JSON_WINDOW_H
#define HUBWIRE_SESSION_JSON_WINDOW_H

#include <stdint.h>

#include "../text.h"

namespace hubwire {

// The descriptor's fixed pieces (keys with their punctuation), kept in one flash string: writing
// one costs a call with a byte argument. Keys other than the first of an object carry their comma.
enum Fragment : uint8_t {
  kFragHead,         // {"p":
  kFragName,         // ,"n":
  kFragFirmware,     // ,"fw":
  kFragChannels,     // ,"ch":[
  kFragChannel,      // {"id":
  kFragAccess,       // ,"a":"
  kFragType,         // ,"t":"
  kFragCount,        // ,"c":
  kFragFields,       // ,"f":[
  kFragReturn,       // ,"rt":"
  kFragUnit,         // ,"u":
  kFragMin,          // ,"min":
  kFragMax,          // ,"max":
  kFragFailsafe,     // ,"fs":
  kFragDescription,  // ,"d":
  kFragField,        // {"n":
};

class JsonWindow {
 public:
  // Copy characters [start, start + len) into out; out may be null to only count and hash.
  JsonWindow(uint16_t start, uint16_t len, uint8_t* out) : start_(start), len_(len), out_(out), pos_(0), hash_(0x811C9DC5UL) {}

  void put(char c);
  void flash(const char* s);  // a flash string (Text's rules), no escaping
  void fragment(Fragment f);
  void text(Text t);  // quoted and escaped
  void number(float v);
  void uinteger(uint32_t v);
  void integer(int32_t v);

  uint16_t length() const { return pos_; }
  // True once every character of the window has been produced (never when only counting).
  bool done() const { return out_ && pos_ >= start_ + len_; }
  // Continue counting from pos (resuming after characters produced by an earlier pass).
  void seek(uint16_t pos) { pos_ = pos; }
  uint32_t hash() const { return hash_; }
  // Remembers the last id marked while inside the window, and where it was (0: none yet).
  void mark(uint8_t id) {
    markId_ = id;
    markPos_ = pos_;
  }
  uint8_t markId() const { return markId_; }
  uint16_t markPos() const { return markPos_; }

 private:
  uint16_t start_, len_;
  uint8_t* out_;
  uint16_t pos_;
  uint32_t hash_;
  uint8_t markId_ = 0;
  uint16_t markPos_ = 0;
};

}  // namespace hubwire

#endif
