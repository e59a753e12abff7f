// Footprint baseline: a sketch that only echoes Serial bytes. Library costs are measured over this.
void setup() { Serial.begin(115200); }

void loop() {
  if (Serial.available()) Serial.write(Serial.read());
}
