// Hubwire's examples/Minimal written with rosserial (a ROS 1 node on the board), as its tutorials
// would have it; built by bench/peers.sh for the like-for-like rows of bench/PEERS.md.
//
//   blink_ms/set  subscribed, std_msgs/UInt16: a new blink_ms; out of 50..5000 it is not taken
//   blink_ms      published, std_msgs/UInt16: blink_ms now, after each write (the answer: the
//                 value written when taken, the old one when not) and once a second (the read)
//   led           service std_srvs/SetBool: switches the blinking, answers success
//   button        published, std_msgs/UInt8: a press of the button on pin 2 (sent once, never repeated)
#include <ros.h>
#include <std_msgs/UInt16.h>
#include <std_msgs/UInt8.h>
#include <std_srvs/SetBool.h>

ros::NodeHandle nh;

uint16_t blinkMs = 500;
bool blinking = true;

std_msgs::UInt16 blinkMsMsg;
ros::Publisher blinkMsPub("blink_ms", &blinkMsMsg);

void publishBlinkMs()
{
  blinkMsMsg.data = blinkMs;
  blinkMsPub.publish(&blinkMsMsg);
}

void setBlinkMs(const std_msgs::UInt16& msg)
{
  if (msg.data >= 50 && msg.data <= 5000)
    blinkMs = msg.data;
  publishBlinkMs();
}
ros::Subscriber<std_msgs::UInt16> blinkMsSub("blink_ms/set", &setBlinkMs);

void setLed(const std_srvs::SetBool::Request& req, std_srvs::SetBool::Response& res)
{
  blinking = req.data;
  res.success = true;
  res.message = "";
}
ros::ServiceServer<std_srvs::SetBool::Request, std_srvs::SetBool::Response> ledServer("led", &setLed);

std_msgs::UInt8 buttonMsg;
ros::Publisher buttonPub("button", &buttonMsg);

void setup()
{
  pinMode(LED_BUILTIN, OUTPUT);
  pinMode(2, INPUT_PULLUP);
  nh.initNode();
  nh.advertise(blinkMsPub);
  nh.advertise(buttonPub);
  nh.subscribe(blinkMsSub);
  nh.advertiseService(ledServer);
}

void loop()
{
  nh.spinOnce();

  static uint32_t publishedAt;
  if (millis() - publishedAt >= 1000) {
    publishedAt = millis();
    publishBlinkMs();
  }

  static uint32_t toggledAt;
  if (millis() - toggledAt >= blinkMs) {
    toggledAt = millis();
    digitalWrite(LED_BUILTIN, blinking && !digitalRead(LED_BUILTIN));
  }

  static bool wasPressed;
  static uint8_t presses;
  bool pressed = digitalRead(2) == LOW;
  if (pressed && !wasPressed) {
    buttonMsg.data = ++presses;
    buttonPub.publish(&buttonMsg);
  }
  wasPressed = pressed;
}
