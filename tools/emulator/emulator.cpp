// hubwire-emulator: runs an example sketch (Rover by default) on Linux, with Serial on a pty, so the
// hub can be tested against the real library code without a board.
//
//   hubwire-emulator --link /tmp/rover     prints "READY /tmp/rover", runs until SIGTERM/SIGINT
//   hubwire-emulator --link /tmp/rover --board-id 0a1b   the board id it reports (1..16 bytes, hex)
//   hubwire-emulator --tcp 0               Serial is a TCP connection instead, as a board on WiFi
//                                          serves it: listens on 127.0.0.1 (port 0: any free one),
//                                          prints "READY socket://127.0.0.1:PORT", takes one hub at a
//                                          time and the next one after it hangs up
//
// SIGUSR2 presses or releases the bumper (pin 2), as a finger would on the real robot. With --tcp,
// SIGHUP drops the hub's connection, as a WiFi link that fails does.
#include <ctype.h>
#include <errno.h>
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/socket.h>
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
volatile sig_atomic_t dropRequests = 0;
uint8_t pinLevel[64];
uint8_t pinModes[64];
struct timespec started;

void onStop(int) { running = 0; }
void onBumper(int) { bumperToggles = bumperToggles + 1; }
void onDrop(int) { dropRequests = dropRequests + 1; }

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
  if (n == 0 && socket_) hangUp();  // the hub closed the connection
  return n == 1 ? b : -1;
}

void EmulatedSerial::hangUp() {
  close(fd_);
  fd_ = -1;
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
      if (socket_) hangUp();  // the hub is gone (EPIPE, ECONNRESET)
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

namespace {
// Serial as one TCP connection at a time on 127.0.0.1:port; returns the listening socket, or -1.
int listenTcp(int port, int* bound) {
  int s = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK, 0);
  int one = 1;
  setsockopt(s, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
  struct sockaddr_in a;
  memset(&a, 0, sizeof(a));
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons((uint16_t)port);
  socklen_t len = sizeof(a);
  if (s < 0 || bind(s, (struct sockaddr*)&a, sizeof(a)) || listen(s, 1) ||
      getsockname(s, (struct sockaddr*)&a, &len)) {
    perror("tcp");
    return -1;
  }
  *bound = ntohs(a.sin_port);
  return s;
}

// A hub waiting to connect is taken once the last one has gone, as a WiFi sketch does.
void acceptHub(int listener) {
  if (Serial.attached()) return;
  int c = accept4(listener, nullptr, nullptr, SOCK_NONBLOCK);
  if (c < 0) return;
  int one = 1;
  setsockopt(c, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
  Serial.attach(c, true);
}

// Serial on a pty linked at link; returns the master, or -1. *slave is kept open by the caller.
int openPty(const char* link, int* slave) {
  int master = posix_openpt(O_RDWR | O_NOCTTY);
  if (master < 0 || grantpt(master) || unlockpt(master)) {
    perror("pty");
    return -1;
  }
  const char* slaveName = ptsname(master);
  // Hold the slave open ourselves so the master never sees a hang-up between hub connections, and
  // make it raw: bytes pass unchanged, as on a real serial port.
  *slave = open(slaveName, O_RDWR | O_NOCTTY);
  struct termios tio;
  tcgetattr(*slave, &tio);
  cfmakeraw(&tio);
  tcsetattr(*slave, TCSANOW, &tio);
  fcntl(master, F_SETFL, fcntl(master, F_GETFL) | O_NONBLOCK);
  unlink(link);
  if (symlink(slaveName, link)) {
    perror("symlink");
    return -1;
  }
  return master;
}
}  // namespace

int main(int argc, char** argv) {
  const char* link = nullptr;
  int tcpPort = -1;
  for (int i = 1; i < argc; ++i) {
    if (!strcmp(argv[i], "--link") && i + 1 < argc) {
      link = argv[++i];
    } else if (!strcmp(argv[i], "--tcp") && i + 1 < argc) {
      tcpPort = atoi(argv[++i]);
    } else if (!strcmp(argv[i], "--board-id") && i + 1 < argc && parseBoardId(argv[i + 1])) {
      ++i;
    } else {
      link = nullptr;
      tcpPort = -1;
      break;
    }
  }
  if (!link == (tcpPort < 0)) {
    fprintf(stderr, "usage: %s (--link PATH | --tcp PORT) [--board-id HEX]\n", argv[0]);
    return 2;
  }
  clock_gettime(CLOCK_MONOTONIC, &started);
  srand((unsigned)(time(nullptr) ^ getpid()));
  signal(SIGPIPE, SIG_IGN);  // a hub that hangs up makes write() fail, not the process die

  int master = -1, slave = -1, listener = -1, port = 0;
  if (link) {
    master = openPty(link, &slave);
    if (master < 0) return 1;
    Serial.attach(master);
  } else {
    listener = listenTcp(tcpPort, &port);
    if (listener < 0) return 1;
  }
  struct sigaction sa;
  memset(&sa, 0, sizeof(sa));
  sa.sa_handler = onStop;
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);
  sa.sa_handler = onBumper;
  sigaction(SIGUSR2, &sa, nullptr);
  sa.sa_handler = onDrop;
  sigaction(SIGHUP, &sa, nullptr);

  setup();
  if (link) {
    printf("READY %s\n", link);
  } else {
    printf("READY socket://127.0.0.1:%d\n", port);
  }
  fflush(stdout);
  sig_atomic_t dropped = 0;
  while (running) {
    if (dropRequests != dropped) {
      dropped = dropRequests;
      if (Serial.attached() && listener >= 0) Serial.hangUp();
    }
    if (listener >= 0) acceptHub(listener);
    loop();
    // Sleep until a byte (or a hub) arrives or 1 ms passes: a loop() at ~1 kHz, idle CPU low.
    struct pollfd p = {Serial.attached() ? Serial.fd() : listener, POLLIN, 0};
    poll(&p, 1, 1);
  }
  if (link) {
    unlink(link);
    close(slave);
    close(master);
  } else {
    if (Serial.attached()) Serial.hangUp();
    close(listener);
  }
  return 0;
}
