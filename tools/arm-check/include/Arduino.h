// Minimal stand-in for the Arduino core's Arduino.h, used only by tools/arm-check/check-arm.sh to
// compile Hubwire for 32-bit ARM (Cortex-M0+ / M4) without any vendor core. Declarations follow
// the public Arduino API (Print, Stream, HardwareSerial, millis, F()); nothing here is meant to
// run. Written from the API documentation, not copied from any core.
#ifndef HUBWIRE_ARM_CHECK_ARDUINO_H
#define HUBWIRE_ARM_CHECK_ARDUINO_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#define ARDUINO_STANDIN 1

// ---- flash strings (no separate address space on ARM) -------------------------------------
#define PROGMEM
#define PGM_P const char*
#define PSTR(s) (s)
#define pgm_read_byte(p) (*(const uint8_t*)(p))
#define pgm_read_word(p) (*(const uint16_t*)(p))
#define pgm_read_dword(p) (*(const uint32_t*)(p))
#define pgm_read_float(p) (*(const float*)(p))
#define pgm_read_ptr(p) (*(void* const*)(p))
#define memcpy_P memcpy
#define strlen_P strlen
#define strcmp_P strcmp
#define strncmp_P strncmp

class __FlashStringHelper;
#define F(string_literal) (reinterpret_cast<const __FlashStringHelper*>(PSTR(string_literal)))

// ---- time ----------------------------------------------------------------------------------
extern "C" {
unsigned long millis(void);
unsigned long micros(void);
void delay(unsigned long ms);
void delayMicroseconds(unsigned int us);
}

// ---- digital pins ----------------------------------------------------------------------------
#define HIGH 0x1
#define LOW 0x0
#define INPUT 0x0
#define OUTPUT 0x1
#define LED_BUILTIN 13
extern "C" {
void pinMode(uint8_t pin, uint8_t mode);
void digitalWrite(uint8_t pin, uint8_t value);
int digitalRead(uint8_t pin);
}

typedef bool boolean;
typedef uint8_t byte;

// ---- Print / Stream --------------------------------------------------------------------------
class Print {
 public:
  virtual ~Print() {}
  virtual size_t write(uint8_t) = 0;
  virtual size_t write(const uint8_t* buffer, size_t size) {
    size_t n = 0;
    while (size--) {
      if (write(*buffer++)) n++;
      else break;
    }
    return n;
  }
  size_t write(const char* str) { return str ? write(reinterpret_cast<const uint8_t*>(str), strlen(str)) : 0; }
  size_t write(const char* buffer, size_t size) { return write(reinterpret_cast<const uint8_t*>(buffer), size); }
  virtual int availableForWrite() { return 0; }
  virtual void flush() {}

  size_t print(const __FlashStringHelper* s) { return print(reinterpret_cast<const char*>(s)); }
  size_t print(const char* s) { return write(s); }
  size_t print(char c) { return write(static_cast<uint8_t>(c)); }
  size_t println() { return write("\r\n"); }
  size_t println(const char* s) { return print(s) + println(); }
  size_t println(const __FlashStringHelper* s) { return print(s) + println(); }
};

class Stream : public Print {
 public:
  virtual int available() = 0;
  virtual int read() = 0;
  virtual int peek() = 0;
  void setTimeout(unsigned long timeout) { timeout_ = timeout; }

 protected:
  unsigned long timeout_ = 1000;
};

class HardwareSerial : public Stream {
 public:
  void begin(unsigned long baud) { (void)baud; }
  void end() {}
  int available() override;
  int read() override;
  int peek() override;
  size_t write(uint8_t) override;
  size_t write(const uint8_t* buffer, size_t size) override;
  int availableForWrite() override;
  void flush() override;
  using Print::write;
  explicit operator bool() { return true; }
};

extern HardwareSerial Serial;

#endif
