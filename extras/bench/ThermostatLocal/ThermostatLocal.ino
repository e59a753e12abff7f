// examples/Thermostat without the hub's channels: its own channels and the same loop, with the
// setpoint, the report and the alarm kept on the board. bench/footprint.sh builds both; the
// difference is what remote(), remoteAction(), remoteEvent() and the calls to them cost.
#include <Hubwire.h>

Hubwire hub(Serial);

float temperature = 20.0f;
bool heating = false;
float setpoint = 21.0f;
uint16_t report = 0;
uint8_t mode = 1;
uint16_t setpoints = 0, reports = 0, alarms = 0, modes = 0, failures = 0;
uint8_t lastFailure = 0;

HUBWIRE_CHANNELS(channels, "thermostat",
  expose("temperature", temperature).unit("C"),
  expose("heating", heating),
  expose("setpoints", setpoints),
  expose("reports", reports),
  expose("alarms", alarms),
  expose("modes", modes),
  expose("failures", failures),
  expose("last_failure", lastFailure));

uint32_t lastAsk = 0;

void setup() {
  Serial.begin(115200);
  hub.begin(channels);
}

void loop() {
  hub.update();
  uint32_t now = millis();
  if (now - lastAsk < 1000) return;
  lastAsk = now;
  heating = mode == 1 && temperature < setpoint;
  temperature += heating ? 0.5f : -0.1f;
  report = (uint16_t)(temperature * 10);
  if (temperature > setpoint + 5.0f) ++alarms;
}
