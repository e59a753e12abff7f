// Missions: a long action the hub starts, follows and may cancel.
//
//   mission(name, m, start, cancel)  the hub starts a run with a goal; start(goal) returns at once
//                                    and the work goes on in loop(), which reports progress with
//                                    hub.progress(m, value) and ends the run with hub.finish(m,
//                                    result) or hub.fail(m, code). When the hub cancels the run,
//                                    cancel() stops the work and the run ends as cancelled.
//
// Here the "drive" mission moves a simulated rover by a distance (metres) at `speed` m/s: progress
// is the distance driven so far, every 100 ms, and the result the distance driven in all. Setting
// `blocked` makes the drive fail with code 1, as a bumper would. A run started while one is going
// is refused (BUSY); the hub is told of every update exactly once and in order, even over a lossy
// line; a run keeps going while the link is down, and its updates follow when the link is back.
//
// Try it on the hub:  hubwire call /dev/ttyACM0 drive 2.0     (a progress bar; Ctrl-C cancels)
// or in Python:       job = board.start("drive", 2.0); job.result()
#include <Hubwire.h>

Hubwire hub(Serial);

hubwire::Mission<float(float), float> drive;  // result: metres driven; goal: metres; progress: metres
float speed = 1.0f;  // m/s
float odometer;      // metres driven since boot
bool blocked;        // set by the hub: the way is blocked, the drive fails

const uint8_t kBlocked = 1;  // the drive's failure code: something is in the way

float goal, driven;  // the run going: its goal and the distance driven so far
uint32_t lastStep, lastReport;

bool startDrive(float metres) {
  if (blocked) return false;  // refused: the hub gets REJECTED
  goal = metres;
  driven = 0;
  lastStep = lastReport = millis();
  digitalWrite(LED_BUILTIN, HIGH);  // "motors on"
  return true;
}

void cancelDrive() { digitalWrite(LED_BUILTIN, LOW); }  // stop; the run ends as cancelled

HUBWIRE_CHANNELS(channels, "missions",
  mission("drive", drive, startDrive, cancelDrive).range(0.1f, 10.0f).unit("m").progressMax(10.0f)
      .describe("drive straight this far"),
  expose("speed", speed).writable().range(0.1f, 2.0f).unit("m/s"),
  expose("odometer", odometer).unit("m"),
  expose("blocked", blocked).writable());

void setup() {
  Serial.begin(115200);
  pinMode(LED_BUILTIN, OUTPUT);
  hub.begin(channels);
}

void loop() {
  hub.update();
  if (!drive.running()) return;
  // A step per pass: never wait here, so that the hub is still answered while the rover drives.
  uint32_t now = millis();
  float step = speed * (float)(now - lastStep) / 1000.0f;
  lastStep = now;
  bool arrived = driven + step >= goal;
  if (arrived) step = goal - driven;
  driven = arrived ? goal : driven + step;  // exactly the goal at the end, whatever the rounding
  odometer += step;
  if (blocked) {
    digitalWrite(LED_BUILTIN, LOW);
    hub.fail(drive, kBlocked);
  } else if (arrived) {
    digitalWrite(LED_BUILTIN, LOW);
    hub.finish(drive, driven);
  } else if (now - lastReport >= 100) {
    lastReport = now;
    hub.progress(drive, driven);  // a newer value replaces one not yet sent
  }
}
