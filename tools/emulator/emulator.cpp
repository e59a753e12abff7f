// hubwire-emulator: runs an example sketch (Rover by default) on Linux, with Serial on a pty, so the
// hub can be tested against the real library code without a board.
//
//   hubwire-emulator --link /tmp/rover     prints "READY /tmp/rover", runs until SIGTERM/SIGINT
//   hubwire-emulator --link /tmp/rover --board-id 0a1b   the board id it reports (1..16 bytes, hex)
//
// SIGUSR2 presses or releases the bumper (pin 2), as a finger would on the real robot.
#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "Arduino.h"

EmulatedSerial Serial;

namespace {
volatile sig_atomic_t running = 1;
volatile sig_atomic_t bumperToggles = 0;
uint8_t pinLevel[64];
uint8_t pinModes[64];
struct timespec started;

void onStop(int) { running = 0; }
void onBumper(int) { bumperToggles = bumperToggles + 1; }

uint64_t nowUs() {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  int64_t ns = (int64_t)(t.tv_sec - started.tv_sec) * 1000000000 + (t.tv_nsec - started.tv_nsec);
  return (uint64_t)(ns / 1000);
}
}  // namespace

int EmulatedSerial::available() {
  if (peeked_ >= 0) return 1;
  struct pollfd p = {fd_, POLLIN, 0};
  return poll(&p, 1, 0) > 0 && (p.revents & POLLIN) ? 1 : 0;
}

int EmulatedSerial::read() {
  if (peeked_ >= 0) {
    int c = peeked_;
    peeked_ = -1;
    return c;
  }
  uint8_t b;
  ssize_t n = ::read(fd_, &b, 1);
  return n == 1 ? b : -1;
}

int EmulatedSerial::peek() {
  if (peeked_ < 0) peeked_ = read();
  return peeked_;
}

size_t EmulatedSerial::write(const uint8_t* data, size_t len) {
  size_t done = 0;
  while (done < len) {
    ssize_t n = ::write(fd_, data + done, len - done);
    if (n > 0) {
      done += (size_t)n;
    } else if (n < 0 && errno == EAGAIN) {
      return done;  // nobody is reading: drop, like a UART with no listener
    } else if (n < 0 && errno != EINTR) {
      return done;
    }
  }
  return done;
}

namespace hubwire {
uint32_t emulatorNonce() {  // a fresh process is a fresh boot
  uint32_t n = 0;
  int fd = open("/dev/urandom", O_RDONLY);
  if (fd >= 0 && ::read(fd, &n, sizeof(n)) != sizeof(n)) n = 0;
  if (fd >= 0) close(fd);
  return n ^ (uint32_t)getpid();
}

uint8_t boardId[16], boardIdLen;  // --board-id: none unless given, like an AVR
uint8_t emulatorBoardId(uint8_t* out) {
  memcpy(out, boardId, boardIdLen);
  return boardIdLen;
}
}  // namespace hubwire

namespace {
// "--board-id 0a1b2c": 1..16 bytes in hex.
bool parseBoardId(const char* hex) {
  size_t n = strlen(hex);
  if (n == 0 || n % 2 || n > 32) return false;
  for (size_t i = 0; i < n / 2; ++i) {
    unsigned v;
    if (sscanf(hex + 2 * i, "%2x", &v) != 1 || !isxdigit((unsigned char)hex[2 * i]) ||
        !isxdigit((unsigned char)hex[2 * i + 1]))
      return false;
    hubwire::boardId[i] = (uint8_t)v;
  }
  hubwire::boardIdLen = (uint8_t)(n / 2);
  return true;
}
}  // namespace

uint32_t millis() { return (uint32_t)(nowUs() / 1000); }
uint32_t micros() { return (uint32_t)nowUs(); }
void pinMode(uint8_t pin, uint8_t mode) {
  pinModes[pin & 63] = mode;
  if (mode == INPUT_PULLUP) pinLevel[pin & 63] = HIGH;
}
void digitalWrite(uint8_t pin, uint8_t value) { pinLevel[pin & 63] = value ? HIGH : LOW; }
int digitalRead(uint8_t pin) {
  if (pin == 2) return (bumperToggles % 2) ? LOW : HIGH;  // pressed after an odd number of SIGUSR2
  return pinLevel[pin & 63];
}
void analogWrite(uint8_t pin, int value) { pinLevel[pin & 63] = value != 0; }
int analogRead(uint8_t) { return 512; }
void tone(uint8_t, unsigned int, unsigned long) {}
void noTone(uint8_t) {}
void delay(unsigned long ms) { usleep((useconds_t)ms * 1000); }

// The sketch itself, compiled unchanged.
#ifndef HUBWIRE_SKETCH
#define HUBWIRE_SKETCH "../../examples/Rover/Rover.ino"
#endif
#include HUBWIRE_SKETCH

int main(int argc, char** argv) {
  const char* link = nullptr;
  for (int i = 1; i < argc; ++i) {
    if (!strcmp(argv[i], "--link") && i + 1 < argc) {
      link = argv[++i];
    } else if (!strcmp(argv[i], "--board-id") && i + 1 < argc && parseBoardId(argv[i + 1])) {
      ++i;
    } else {
      fprintf(stderr, "usage: %s --link PATH [--board-id HEX]\n", argv[0]);
      return 2;
    }
  }
  if (!link) {
    fprintf(stderr, "usage: %s --link PATH [--board-id HEX]\n", argv[0]);
    return 2;
  }
  clock_gettime(CLOCK_MONOTONIC, &started);
  srand((unsigned)(time(nullptr) ^ getpid()));

  int master = posix_openpt(O_RDWR | O_NOCTTY);
  if (master < 0 || grantpt(master) || unlockpt(master)) {
    perror("pty");
    return 1;
  }
  const char* slaveName = ptsname(master);
  // Hold the slave open ourselves so the master never sees a hang-up between hub connections, and
  // make it raw: bytes pass unchanged, as on a real serial port.
  int slave = open(slaveName, O_RDWR | O_NOCTTY);
  struct termios tio;
  tcgetattr(slave, &tio);
  cfmakeraw(&tio);
  tcsetattr(slave, TCSANOW, &tio);
  fcntl(master, F_SETFL, fcntl(master, F_GETFL) | O_NONBLOCK);
  Serial.attach(master);

  unlink(link);
  if (symlink(slaveName, link)) {
    perror("symlink");
    return 1;
  }
  struct sigaction sa;
  memset(&sa, 0, sizeof(sa));
  sa.sa_handler = onStop;
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);
  sa.sa_handler = onBumper;
  sigaction(SIGUSR2, &sa, nullptr);

  setup();
  printf("READY %s\n", link);
  fflush(stdout);
  while (running) {
    loop();
    struct pollfd p = {master, POLLIN, 0};
    poll(&p, 1, 1);  // sleep until a byte arrives or 1 ms passes: a loop() at ~1 kHz, idle CPU low
  }
  unlink(link);
  close(slave);
  close(master);
  return 0;
}
