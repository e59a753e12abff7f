// Minimal's own loop without any hub: what the sketch part of Minimal costs by itself.
uint16_t blinkMs = 500;
bool blinking = true;
volatile uint8_t sink;
void setup() {
  Serial.begin(115200);
  pinMode(LED_BUILTIN, OUTPUT);
  pinMode(2, INPUT_PULLUP);
}
void loop() {
  if (Serial.available()) Serial.write(Serial.read());
  static uint32_t toggledAt;
  if (millis() - toggledAt >= blinkMs) {
    toggledAt = millis();
    digitalWrite(LED_BUILTIN, blinking && !digitalRead(LED_BUILTIN));
  }
  static bool wasPressed;
  static uint8_t presses;
  bool pressed = digitalRead(2) == LOW;
  if (pressed && !wasPressed) sink = ++presses;
  wasPressed = pressed;
}
