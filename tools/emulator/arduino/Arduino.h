// Just enough of the Arduino API, on Linux, to run a Hubwire sketch as a device process.
// Serial is a pseudo-terminal (see emulator.cpp); pins are simulated in memory.
#ifndef HUBWIRE_EMULATOR_ARDUINO_H
#define HUBWIRE_EMULATOR_ARDUINO_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

class __FlashStringHelper;
#define F(s) (reinterpret_cast<const __FlashStringHelper*>(s))
#define PROGMEM

enum { LOW = 0, HIGH = 1 };
enum { INPUT = 0, OUTPUT = 1, INPUT_PULLUP = 2 };
const uint8_t LED_BUILTIN = 13;
const uint8_t A0 = 14;
const uint8_t NUM_DIGITAL_PINS = 20;  // an Uno's (Actions checks its argument against it)

class Stream {
 public:
  virtual ~Stream() {}
  virtual int available() = 0;
  virtual int read() = 0;
  virtual int peek() = 0;
  virtual size_t write(uint8_t b) = 0;
  virtual size_t write(const uint8_t* data, size_t len) = 0;
  virtual int availableForWrite() = 0;
  virtual void flush() {}
};

class EmulatedSerial : public Stream {
 public:
  void begin(unsigned long baud) { (void)baud; }
  int available() override;
  int read() override;
  int peek() override;
  size_t write(uint8_t b) override { return write(&b, 1); }
  size_t write(const uint8_t* data, size_t len) override;
  int availableForWrite() override { return 4096; }
  // fd: a pty master, or (socket) a hub's TCP connection, closed when the hub hangs up.
  void attach(int fd, bool socket = false) {
    fd_ = fd;
    socket_ = socket;
    peeked_ = -1;
  }
  bool attached() const { return fd_ >= 0; }
  int fd() const { return fd_; }
  void hangUp();

 private:
  int fd_ = -1;
  bool socket_ = false;
  int peeked_ = -1;
};
extern EmulatedSerial Serial;

uint32_t millis();
uint32_t micros();
void pinMode(uint8_t pin, uint8_t mode);
void digitalWrite(uint8_t pin, uint8_t value);
int digitalRead(uint8_t pin);
void analogWrite(uint8_t pin, int value);
int analogRead(uint8_t pin);
void tone(uint8_t pin, unsigned int frequency, unsigned long duration = 0);
void noTone(uint8_t pin);
void delay(unsigned long ms);

#endif
