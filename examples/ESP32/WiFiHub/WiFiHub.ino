// WiFiHub: an ESP32 serves the Hubwire protocol over WiFi instead of a cable.
//
// Hubwire talks through any Stream; here it is the TCP connection of the hub, which connects with
//   hubwire info socket://wifihub.local:5000
// When the connection drops (WiFi lost, hub restarted) the board waits for the next one and the hub
// connects again by itself; meanwhile the link is lost as on a cable, so failsafes apply.
//
// ESP32 family only (WiFi.h, ESPmDNS.h). Set your network below.
#include <ESPmDNS.h>
#include <WiFi.h>

#include <Hubwire.h>

const char* const kSsid = "your-network";
const char* const kPassword = "your-password";
const uint16_t kPort = 5000;

WiFiServer server(kPort);
WiFiClient client;    // the hub's connection, when there is one: the same object throughout,
Hubwire hub(client);  // so the session keeps reading it across reconnections

float speed;                       // a motor's speed, 0 when the hub goes silent
uint32_t uptimeS;                  // seconds since boot, streamable
hubwire::Event<uint8_t> button;    // presses of the BOOT button (GPIO 9 on an ESP32-C3)

#if defined(CONFIG_IDF_TARGET_ESP32C3)
const uint8_t kButtonPin = 9;
#else
const uint8_t kButtonPin = 0;
#endif

HUBWIRE_CHANNELS(channels, device("wifihub").firmware("1.0.0"),
  expose("speed", speed).writable().range(-1.0f, 1.0f).failsafe(0.0f),
  expose("uptime_s", uptimeS).streamable().unit("s"),
  event("button", button));

void setup() {
  pinMode(kButtonPin, INPUT_PULLUP);
  WiFi.mode(WIFI_STA);
  WiFi.setAutoReconnect(true);  // the station joins again after the access point drops it
  WiFi.begin(kSsid, kPassword);
  MDNS.begin("wifihub");        // wifihub.local
  server.begin();
  server.setNoDelay(true);
  hub.begin(channels);
}

void loop() {
  // The hub went away (or never came): take the next one that connects.
  if (!client.connected()) {
#if defined(ESP_ARDUINO_VERSION_MAJOR) && ESP_ARDUINO_VERSION_MAJOR >= 3
    WiFiClient next = server.accept();
#else
    WiFiClient next = server.available();
#endif
    if (next) {
      client = next;
      client.setNoDelay(true);  // frames are small: send each at once
    }
  }
  hub.update();  // answers the hub; never blocks (reads nothing while no hub is connected)

  uptimeS = millis() / 1000;
  static bool wasPressed;
  static uint8_t presses;
  bool pressed = digitalRead(kButtonPin) == LOW;
  if (pressed && !wasPressed) hub.emit(button, ++presses);
  wasPressed = pressed;
}
