// Soak: the device the reliability soak (host/hubwire/testing/faultlink/soak.py) runs against, in
// the emulator (build/emulator/hubwire-soak-emulator) so the soak exercises the real library.
//
// Rover's motors, sensors, bumper and selftest, plus a writable u32 `token`: the hub writes
// strictly increasing tokens, and the sketch itself counts how each one was applied. A token not
// above the last one applied means a write was applied twice (or out of order): `twice`. Tokens
// skipped between two applied ones were never applied (a write that timed out): `gaps`. The hub's
// check needs no inference: twice must be 0 and applied + never applied must equal what it sent.
//
// Large values: `blob` (40 bytes, more than one 32-byte frame) travels in fragments both ways. The
// hub writes blobs with strictly increasing tokens and sum = FNV-1a 32 of the token's 4 bytes
// (little-endian) then the 32 data bytes; the sketch counts blobs applied, corrupt (sum wrong: a
// torn or damaged value), twice and gaps, as for `token`, and the hub reads blobs back whole.
//
// The other direction (the hub's channels): while the hub sets `hub_load`, the sketch writes
// strictly increasing tokens into the hub's `tally` and calls the hub's `bump` with every 4th (the
// hub returns it + 1), one request at a time, every 20 ms; the hub sends strictly increasing `tick`
// events. The sketch counts what became of each: acked or failed, right or wrong answers, ticks
// applied twice or skipped.
//
// Missions: the hub starts `count` with a goal n (u16) over and over; the sketch reports progress
// 1, 2, ... below n, a step every 5 ms (a newer value replaces one not yet sent), and finishes with
// n * 1000 + its run number; a goal of 999 fails with code 9 at step 3, a goal of 0 is refused. It
// counts the starts it accepted (`missionStarts`): a start applied twice shows there.
// (33 channels: the soak's emulator is built with HUBWIRE_MAX_CHANNELS=40, CMakeLists.txt.)
#include <Hubwire.h>

Hubwire hub(Serial);

float left, right;  // m/s, -1..1
uint16_t rangeCm[4];
uint16_t batteryMv = 7400;
hubwire::Event<bool> bumper;
uint16_t failsafes;  // link losses the device declared (each fired the failsafe)
uint32_t applied;    // writes of left and right applied
uint32_t uptime;     // millis() as of the last loop(): lets the hub relate the two clocks
uint32_t failsafeAt;  // millis() when the failsafe last fired (how fast a dead link is noticed)

uint32_t token;          // the last token written by the hub
uint32_t lastToken;      // the last token applied (0: none since boot)
uint32_t firstToken;     // the first token applied since boot
uint32_t tokensApplied;  // onChange calls for token
uint32_t twice;          // tokens not above the last applied one: applied twice or out of order
uint32_t gaps;           // tokens skipped between two applied ones

struct Blob {
  uint32_t token;
  uint8_t data[32];
  uint32_t sum;
} blob;
// blob_counts: applied, corrupt, twice, gaps (one channel: the table is at HUBWIRE_MAX_CHANNELS)
uint32_t blobCounts[4];
uint32_t& blobsApplied = blobCounts[0];
uint32_t& blobsCorrupt = blobCounts[1];
uint32_t& blobsTwice = blobCounts[2];
uint32_t& blobsGaps = blobCounts[3];
uint32_t lastBlob;

bool hubLoad;             // set by the hub: drive the hub's channels
uint32_t tallyToken;      // the last token written to the hub's tally (1, 2, 3, ... per boot)
uint32_t tallyAcked, tallyFailed;
hubwire::RemoteAction<uint32_t(uint32_t)> bump;
uint32_t bumpArg, bumpOk, bumpWrong, bumpFailed;
uint32_t tick;            // the hub's events: strictly increasing
uint32_t ticks, tickFirst, tickLast, tickTwice, tickGaps;
uint8_t lastHubFailure;
uint8_t hubQueuedNow;     // hub.hubQueued() as of the last loop(): 0 once every request ended
uint32_t hubAt;

hubwire::Mission<uint32_t(uint16_t), uint16_t> count;
uint16_t countGoal, countStep;
uint32_t countAt;
uint32_t missionStarts;

bool startCount(uint16_t goal) {
  if (goal == 0) return false;  // refused: REJECTED
  ++missionStarts;
  countGoal = goal;
  countStep = 0;
  countAt = millis();
  return true;
}
void cancelCount() {}  // nothing to stop: the run ends as cancelled

void runCount() {
  if (!count.running() || millis() - countAt < 5) return;
  countAt = millis();
  ++countStep;
  if (countGoal == 999 && countStep == 3) hub.fail(count, 9);
  else if (countStep >= countGoal) hub.finish(count, (uint32_t)countGoal * 1000 + count.run());
  else hub.progress(count, countStep);
}

void countWrite() { ++applied; }

void tallyDone() { ++tallyAcked; }
void tallyFail(uint8_t code) { ++tallyFailed; lastHubFailure = code; }
void bumped(uint32_t r) { if (r == bumpArg + 1) ++bumpOk; else ++bumpWrong; }
void bumpFail(uint8_t code) { ++bumpFailed; lastHubFailure = code; }

void tickChanged() {
  ++ticks;
  if (tickLast == 0) {
    tickFirst = tick;
  } else if (tick <= tickLast) {
    ++tickTwice;
    return;
  } else {
    tickGaps += tick - tickLast - 1;
  }
  tickLast = tick;
}

// One device request at a time (the queue empty), so every token's fate is known on its own.
void driveHub() {
  if (!hubLoad || !hub.hubBinding().ok() || hub.hubQueued() != 0 || millis() - hubAt < 20) return;
  hubAt = millis();
  ++tallyToken;
  hub.write(tallyToken, tallyDone, tallyFail);
  if (tallyToken % 4 == 0) {
    bumpArg = tallyToken;
    hub.call(bump, bumpArg, bumped, bumpFail);
  }
}

void tokenChanged() {
  ++tokensApplied;
  if (lastToken == 0) {
    firstToken = token;
  } else if (token <= lastToken) {
    ++twice;
    return;
  } else {
    gaps += token - lastToken - 1;
  }
  lastToken = token;
}

void blobChanged() {
  ++blobsApplied;
  uint32_t h = 2166136261UL;
  for (uint8_t i = 0; i < 4; ++i) h = (h ^ (uint8_t)(blob.token >> (8 * i))) * 16777619UL;
  for (uint8_t i = 0; i < sizeof(blob.data); ++i) h = (h ^ blob.data[i]) * 16777619UL;
  if (h != blob.sum) {
    ++blobsCorrupt;
    return;
  }
  if (lastBlob != 0 && blob.token <= lastBlob) {
    ++blobsTwice;
    return;
  }
  if (lastBlob != 0) blobsGaps += blob.token - lastBlob - 1;
  lastBlob = blob.token;
}

uint8_t selftest(uint8_t count) {
  uint8_t queued = 0;
  for (uint8_t i = 0; i < count; ++i)
    if (hub.emit(bumper, i % 2 == 0)) ++queued;
  return queued;
}

void stopMotors() {
  ++failsafes;
  failsafeAt = millis();
}

HUBWIRE_CHANNELS(channels, device("soak").firmware("1.0.0"),
  expose("left", left).writable().streamable().range(-1.0f, 1.0f).failsafe(0.0f).onChange(countWrite),
  expose("right", right).writable().streamable().range(-1.0f, 1.0f).failsafe(0.0f).onChange(countWrite),
  expose("range", rangeCm).streamable().unit("cm"),
  expose("battery", batteryMv).streamable().unit("mV"),
  event("bumper", bumper),
  action("selftest", selftest),
  expose("failsafes", failsafes),
  expose("applied", applied),
  expose("uptime", uptime),
  expose("failsafe_at", failsafeAt),
  expose("token", token).writable().onChange(tokenChanged),
  expose("last_token", lastToken),
  expose("first_token", firstToken),
  expose("tokens_applied", tokensApplied),
  expose("twice", twice),
  expose("gaps", gaps),
  expose("blob", blob, "token:u32,data:u8[32],sum:u32").writable().onChange(blobChanged),
  expose("blob_counts", blobCounts),
  expose("hub_load", hubLoad).writable(),
  expose("hub_queued_now", hubQueuedNow),
  expose("tally_token", tallyToken),
  expose("tally_acked", tallyAcked),
  expose("tally_failed", tallyFailed),
  expose("bump_ok", bumpOk),
  expose("bump_wrong", bumpWrong),
  expose("bump_failed", bumpFailed),
  expose("ticks", ticks),
  expose("tick_first", tickFirst),
  expose("tick_last", tickLast),
  expose("tick_twice", tickTwice),
  expose("tick_gaps", tickGaps),
  expose("last_hub_failure", lastHubFailure),
  mission("count", count, startCount, cancelCount).describe("progress 1..n-1, result n * 1000 + run"),
  expose("missionStarts", missionStarts),
  remote("tally", tallyToken).writeOnly(),
  remoteAction("bump", bump),
  remoteEvent("tick", tick).onChange(tickChanged));

// Stand-in sensors with known bounds (the soak checks every streamed sample against them).
void readSensors() {
  static uint32_t at;
  if (millis() - at < 20) return;
  at = millis();
  uint16_t load = (uint16_t)((fabs(left) + fabs(right)) * 100);  // 0..200
  for (uint8_t i = 0; i < 4; ++i) rangeCm[i] = (uint16_t)(100 + 50 * i + load / 11);
  batteryMv = (uint16_t)(7400 - load);
}

void setup() {
  Serial.begin(115200);
  hub.onLinkLost(stopMotors);
  hub.begin(channels);
}

void loop() {
  uptime = millis();
  hub.update();
  readSensors();
  driveHub();
  runCount();
  hubQueuedNow = hub.hubQueued();
}
