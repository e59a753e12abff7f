// Thermostat: the board asks the hub for its setpoint, writes a report into a hub value, calls a hub
// action and takes the hub's events, besides exposing its own channels. The hub side is in the
// README ("Both directions"). Counters are channels too, so that a test can tell what happened.
#include <Hubwire.h>

Hubwire hub(Serial);

float temperature = 20.0f;  // our own reading, simulated: drifts toward the heater's state
bool heating = false;
float setpoint = 0.0f;      // the hub's "setpoint", requested every second
uint16_t report = 0;        // written into the hub's "report": temperature in tenths of a degree
uint8_t mode = 0;           // the hub's "mode" events land here: 0 off, 1 heat
hubwire::RemoteAction<bool(float)> raiseAlarm;  // the hub's action "alarm": told the temperature
// (not called `alarm`: POSIX has an alarm() that ESP32 and Linux builds see)

uint16_t setpoints = 0, reports = 0, alarms = 0, modes = 0, failures = 0;
uint8_t lastFailure = 0;

void setpointArrived() { ++setpoints; }
void reportAcked() { ++reports; }
void alarmAnswered(bool handled) { if (handled) ++alarms; }
void failed(uint8_t code) { ++failures; lastFailure = code; }
void modeChanged() { ++modes; }

HUBWIRE_CHANNELS(channels, "thermostat",
  expose("temperature", temperature).unit("C"),
  expose("heating", heating),
  expose("setpoints", setpoints),
  expose("reports", reports),
  expose("alarms", alarms),
  expose("modes", modes),
  expose("failures", failures),
  expose("last_failure", lastFailure),
  remote("setpoint", setpoint).unit("C"),
  remote("report", report).writeOnly(),
  remoteAction("alarm", raiseAlarm),
  remoteEvent("mode", mode).onChange(modeChanged));

uint32_t lastAsk = 0;

void setup() {
  Serial.begin(115200);
  hub.begin(channels);
}

void loop() {
  hub.update();  // never blocks; requests below are queued and answered through the callbacks
  uint32_t now = millis();
  if (now - lastAsk < 1000 || !hub.hubBinding().ok()) return;
  lastAsk = now;
  heating = mode == 1 && temperature < setpoint;
  temperature += heating ? 0.5f : -0.1f;
  hub.request(setpoint, setpointArrived, failed);
  report = (uint16_t)(temperature * 10);
  hub.write(report, reportAcked, failed);
  if (temperature > setpoint + 5.0f) hub.call(raiseAlarm, temperature, alarmAnswered, failed);
}
