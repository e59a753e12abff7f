// The Arduino-only part of the library: the core's seam bound to a Stream and millis(), and where
// a per-boot nonce comes from.
#include "Hubwire.h"

// ESP-IDF 5 (arduino-esp32 3.x) no longer declares esp_random() through esp_system.h; the header
// of its own exists from IDF 4.1 on, and older cores get it through Arduino.h.
#if defined(ESP32) && defined(__has_include)
#if __has_include(<esp_random.h>)
#include <esp_random.h>
#endif
#endif

namespace hubwire {

int portRead(Port& p) { return p.stream.read(); }
void portWrite(Port& p, const uint8_t* data, size_t len) { p.stream.write(data, len); }
size_t portWritable(Port& p) {
  int n = p.stream.availableForWrite();
  // A transmit buffer as empty as it has ever been will not get emptier: a frame larger than the
  // whole buffer goes now (write() waits for the rest) instead of never. The same rule lets frames
  // go on cores that never implement availableForWrite() (always 0), where room is unknown.
  if (n < p.mostRoom) return (size_t)n;
  p.mostRoom = (uint8_t)(n > 255 ? 255 : n);
  return 0xFFFF;
}
uint32_t portMillis(Port&) { return ::millis(); }
#if defined(__AVR__) && defined(TCNT0)
// Timer 0's count (what micros() reads on the classic AVRs) under the milliseconds: as good for
// entropy as micros(), without its 74 bytes (millis() is linked anyway).
uint32_t portMicros(Port&) { return ((uint32_t)::millis() << 8) | TCNT0; }
#else
uint32_t portMicros(Port&) { return ::micros(); }
#endif

// The board id (PROTOCOL 3.4): the chip's own unique id where the core offers one, so two boards
// running one sketch keep distinct names on the hub; a build may supply its own (the emulator
// does); an AVR has none, unless the sketch sets HUBWIRE_BOARD_ID_EEPROM to an EEPROM address
// where a random id is kept (4 bytes, drawn on the first boot).
#if defined(HUBWIRE_BOARD_ID_SOURCE)
uint8_t HUBWIRE_BOARD_ID_SOURCE(uint8_t* out);
uint8_t portBoardId(Port&, uint8_t* out) { return HUBWIRE_BOARD_ID_SOURCE(out); }
#elif defined(ESP32)
uint8_t portBoardId(Port&, uint8_t* out) {
  uint64_t mac = ESP.getEfuseMac();  // the factory MAC, unique per chip
  for (uint8_t i = 0; i < 6; ++i) out[i] = (uint8_t)(mac >> (8 * i));
  return 6;
}
#elif defined(ARDUINO_ARCH_RP2040) && defined(__has_include) && __has_include(<pico/unique_id.h>)
}  // namespace hubwire
#include <pico/unique_id.h>
namespace hubwire {
uint8_t portBoardId(Port&, uint8_t* out) {
  pico_unique_board_id_t id;  // the flash chip's 64-bit unique id
  pico_get_unique_board_id(&id);
  for (uint8_t i = 0; i < 8; ++i) out[i] = id.id[i];
  return 8;
}
#elif defined(ARDUINO_ARCH_STM32)
uint8_t portBoardId(Port&, uint8_t* out) {
  uint32_t w[3] = {HAL_GetUIDw0(), HAL_GetUIDw1(), HAL_GetUIDw2()};  // the 96-bit device UID
  for (uint8_t i = 0; i < 12; ++i) out[i] = (uint8_t)(w[i / 4] >> (8 * (i % 4)));
  return 12;
}
#elif defined(__IMXRT1062__)
uint8_t portBoardId(Port&, uint8_t* out) {
  uint32_t w[2] = {HW_OCOTP_CFG0, HW_OCOTP_CFG1};  // the i.MX RT's 64-bit unique id fuses
  for (uint8_t i = 0; i < 8; ++i) out[i] = (uint8_t)(w[i / 4] >> (8 * (i % 4)));
  return 8;
}
#elif defined(__AVR__) && defined(HUBWIRE_BOARD_ID_EEPROM)
}  // namespace hubwire
#include <avr/eeprom.h>
namespace hubwire {
uint8_t portBoardId(Port&, uint8_t* out) {
  uint8_t* at = (uint8_t*)(HUBWIRE_BOARD_ID_EEPROM);
  eeprom_read_block(out, at, 4);
  if ((out[0] & out[1] & out[2] & out[3]) == 0xFF) {  // a blank EEPROM: draw the id once
    uint32_t id = ::micros() ^ ((uint32_t)::millis() << 16);  // when the hub first asks varies
    for (uint8_t i = 0; i < 4; ++i) out[i] = (uint8_t)(id >> (8 * i));
    eeprom_update_block(out, at, 4);
  }
  return 4;
}
#else
uint8_t portBoardId(Port&, uint8_t*) { return 0; }
#endif

#if defined(__AVR__) && !defined(HUBWIRE_NONCE_SOURCE)
// Survives a reset (not a power cycle, where RAM starts random anyway), so each boot differs. One
// byte is enough for that (the nonce also mixes in the hub's nonce and the time the hub is first
// heard); counting in four cost 28 B more code.
static uint8_t bootCounter __attribute__((section(".noinit")));
#elif defined(__AVR__)
static uint32_t bootCounter __attribute__((section(".noinit")));
#else
static uint32_t bootCounter;
#endif

#if defined(HUBWIRE_NONCE_SOURCE)
uint32_t HUBWIRE_NONCE_SOURCE();  // a build may supply its own entropy (the Linux emulator does)
#endif

uint32_t bootNonce() {
#if defined(HUBWIRE_NONCE_SOURCE)
  bootCounter ^= HUBWIRE_NONCE_SOURCE();
#elif defined(ESP32)
  bootCounter ^= esp_random();
#endif
  // Differs from the last boot; Session mixes in the moment the hub is first heard and its nonce.
  return ++bootCounter;
}

}  // namespace hubwire
