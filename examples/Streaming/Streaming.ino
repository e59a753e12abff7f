// Streaming: the hub subscribes to sensor readings at the rate it wants.
//
// A streamable channel can be read once, or subscribed to: the hub asks for an interval and the
// board sends a sample every interval until the hub unsubscribes or the link is lost. Each sample
// carries the milliseconds since the previous one, so the hub knows the rate the board achieved,
// not just the one it asked for. Up to HUBWIRE_MAX_STREAMS (default 4) channels stream at once,
// at most one sample per HUBWIRE_MIN_STREAM_INTERVAL_MS (default 10 ms) each.
//
// Try it on the hub:  hubwire watch /dev/ttyACM0
// or in Python:       for s in board.stream("light", hz=20): print(s)
#include <Hubwire.h>

Hubwire hub(Serial);

uint16_t light;   // a light sensor (LDR divider) on A0: 0..1023
uint32_t uptime;  // seconds since the board started

HUBWIRE_CHANNELS(channels, "streaming",
  expose("light", light).streamable().describe("A0 raw, 0..1023"),
  expose("uptime", uptime).streamable().unit("s"));

void setup() {
  Serial.begin(115200);
  hub.begin(channels);
}

void loop() {
  hub.update();  // sends the samples that are due, read from the variables as they are now
  // Keep the variables fresh; Hubwire never calls your code to take a sample.
  light = analogRead(A0);
  uptime = millis() / 1000;
}
