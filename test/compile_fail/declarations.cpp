// Declarations the library must refuse when the sketch compiles, one per HUBWIRE_CASE; CMakeLists.txt
// compiles each case and expects the compiler's message to say why. Case 0 is the control: the same
// file with correct declarations must compile. A case adds one declaration (CASE) to the control's
// table, or compiles the control with a setting too small for it (its flags in CMakeLists.txt).
#include "hubwire/channels/declare.h"
#include "hubwire/session/session.h"

using namespace hubwire;

struct Wide {
  uint8_t b[HUBWIRE_MAX_VALUE + 1];
};
struct Frameful {  // a mission's goal, result or progress too large for one frame
  uint8_t b[HUBWIRE_MAX_PAYLOAD];
};
struct Pose {
  float x;
  uint8_t ok;
  int16_t t[2];
};
struct Real {
  float v;
};
double big[200];  // 1600 bytes: above HUBWIRE_MAX_VALUE
uint8_t fits[HUBWIRE_MAX_PAYLOAD - 2];
uint64_t wide;
Wide wideStruct;
Pose pose;
Real real;
char longText[HUBWIRE_MAX_PAYLOAD - 1];
char text[HUBWIRE_MAX_PAYLOAD - 2];
uint16_t level;
float ratio;
uint8_t small;
int16_t whole;
List<int16_t, 4> list;
Event<uint32_t> fourBytes;
int32_t answer(int16_t v) { return v; }
uint64_t wideAnswer() { return 0; }
List<uint32_t, 2> twoWords() { return List<uint32_t, 2>(); }  // 9 bytes on the wire

void setLevel(uint8_t) {}
void changed() {}
Mission<float(float), float> drive;
bool startDrive(float) { return true; }
void stopDrive() {}
Mission<void(), void> home;
void startHome() {}
Mission<Frameful(float), float> wideResult;
Mission<float(float), Frameful> wideProgress;
Mission<float(Frameful), float> wideGoal;
bool startWide(Frameful) { return true; }

#if HUBWIRE_CASE == 0 || HUBWIRE_CASE == 7 || HUBWIRE_CASE == 8 || HUBWIRE_CASE == 20
#define CASE  // the control alone (7, 8, 20: with a setting too small for it; 20: 6 channels for its 9)
#elif HUBWIRE_CASE == 1
#define CASE , expose("big", big)
#elif HUBWIRE_CASE == 2
#define CASE , expose("wide", wide)
#elif HUBWIRE_CASE == 3
#define CASE , expose("s", wideStruct, "b:u8[32]")
#elif HUBWIRE_CASE == 4
#define CASE , expose("s", longText)
#elif HUBWIRE_CASE == 5
#define CASE , action("wide", wideAnswer)
#elif HUBWIRE_CASE == 6
#define CASE , expose("s", text).range(0, 1)  // strings have no range
#elif HUBWIRE_CASE == 9
#define CASE , event("e2", fourBytes).writable()  // nothing to write into
#elif HUBWIRE_CASE == 10
#define CASE , control("c", setLevel).streamable()  // nothing to read
#elif HUBWIRE_CASE == 11
#define CASE , control("c", setLevel).onChange(changed)  // would replace the control's function
#elif HUBWIRE_CASE == 12
#define CASE , action("a", answer).failsafe(0)  // calling an action on link loss is not a failsafe
#elif HUBWIRE_CASE == 13
#define CASE , action("a", answer).writable()
// Struct layouts: the control declares pose with its right layout; these differ only in the text.
#elif HUBWIRE_CASE == 14
#define CASE , expose("r", real, "v:u8")  // a float is not a u8
#elif HUBWIRE_CASE == 15
#define CASE , expose("p", pose, "x:f32,ok:u8")  // misses t:i16[2]
#elif HUBWIRE_CASE == 16
#define CASE , expose("p", pose, "x:f32,ok:u9,t:i16[2]")  // no type u9
#elif HUBWIRE_CASE == 17
#define CASE , expose("p", pose, "")
#elif HUBWIRE_CASE == 18
#define CASE , expose("p", pose, "x:f32,ok:u8,t:i16[2")
#elif HUBWIRE_CASE == 19
#define CASE , expose("p", pose, "x:f32,ok:u8,t:i16[2],")
// 21..23 (with HUBWIRE_MAX_CHANNELS=254): the `many` table below.
#elif HUBWIRE_CASE == 24
#define CASE , expose("2fast", level)  // names start with a letter or _
#elif HUBWIRE_CASE == 25
#define CASE , expose("a_name_of_thirty_three_characters", level)
#elif HUBWIRE_CASE == 26
#define CASE , expose("fits", level)  // the control has one
#elif HUBWIRE_CASE == 27
#define CASE , expose("lo_hi", level).writable().range(9, 1)
#elif HUBWIRE_CASE == 28
#define CASE , event("e2", fourBytes).range(0, 1)  // the sketch sets an event's value
#elif HUBWIRE_CASE == 29
#define CASE , expose("small", small).writable().range(0, 256)  // 256 is no uint8_t
#elif HUBWIRE_CASE == 30
#define CASE , expose("whole", whole).writable().failsafe(1.5)  // an int16_t cannot hold 1.5
#elif HUBWIRE_CASE == 31
#define CASE , expose("s", pose, "x:f32,ok:u8,t:i16[2]").failsafe(0)  // a struct has no one value
#elif HUBWIRE_CASE == 32
#define TEXT50 "a text of fifty characters, ten words and no more."
#define CASE , expose("long", level).describe(TEXT50 TEXT50 TEXT50 TEXT50 TEXT50 "123456")  // 256
#elif HUBWIRE_CASE == 33
#define CASE , mission("m", wideResult, startDrive, stopDrive)  // a result is a scalar: one frame
#elif HUBWIRE_CASE == 34
#define CASE , mission("m", wideProgress, startDrive, stopDrive)  // so is progress
#elif HUBWIRE_CASE == 35
#define CASE , mission("m", wideGoal, startWide, stopDrive)  // and a goal
#elif HUBWIRE_CASE == 36
#define CASE , mission("m", drive, startDrive, stopDrive).failsafe(0.0f)  // the sketch stops it
#elif HUBWIRE_CASE == 37
#define CASE , mission("m", drive, startDrive, stopDrive).writable()  // started, not written
#elif HUBWIRE_CASE == 38
#define CASE , mission("m", drive, startDrive, stopDrive).streamable()  // progress is its stream
#elif HUBWIRE_CASE == 39
#define CASE , expose("x", real, "v:f32").progressMax(1.0f)  // no progress
#elif HUBWIRE_CASE == 40
#define CASE , mission("m", home, startHome, stopDrive).range(0, 1)  // no goal, no range
#elif HUBWIRE_CASE == 41
#define CASE , expose("l", list).writable().failsafe(0)  // which length would it take?
#elif HUBWIRE_CASE == 42
#define CASE , action("two", twoWords)
#elif HUBWIRE_CASE == 43
#define CASE , expose("nan", ratio).writable().range(__builtin_nanf(""), 1.0f)  // float ranges rely on this
// 44..48: the mistakes a first sketch makes (on the Uno an int is 16 bits: -1 once passed for 65535).
#elif HUBWIRE_CASE == 44
#define CASE , expose("minus", level).writable().failsafe(-1)  // a uint16_t has no -1
#elif HUBWIRE_CASE == 45
#define CASE , expose("out", level).writable().range(100, 900).failsafe(50)
#elif HUBWIRE_CASE == 46
#define CASE , expose("out", level).writable().failsafe(50).range(100, 900)  // either order
#elif HUBWIRE_CASE == 47
#define CASE , expose("neg", level).writable().range(-5, 900)  // not "min is greater than max"
#elif HUBWIRE_CASE == 48
#define CASE , expose("s2", text).failsafe(0)  // strings have no failsafe
#elif HUBWIRE_CASE == 49  // 64 channels with 250-character descriptions: a 21 KB descriptor
#define D50 "a description of fifty characters, ten times over. "
#define ONE(n) , expose(#n, ratio).describe(D50 D50 D50 D50 D50)
#define EIGHT(p) ONE(p##0) ONE(p##1) ONE(p##2) ONE(p##3) ONE(p##4) ONE(p##5) ONE(p##6) ONE(p##7)
#define CASE EIGHT(a) EIGHT(b) EIGHT(c) EIGHT(d) EIGHT(e) EIGHT(f) EIGHT(g) EIGHT(h)
#else
#define CASE
#endif

HUBWIRE_CHANNELS(channels, device("control").firmware("1.0"),
  control("level", setLevel).range(1, 9).failsafe(1).unit("%").describe("a control's options"),
  expose("fits", fits),
  expose("text", text).writable(),
  event("e", fourBytes),
  action("answer", answer).range(-5, 5),
  expose("pose", pose, "x:f32,ok:u8,t:i16[2]").writable().streamable(),
  expose("a_name_of_thirty_two_characters_", real, "v:f32"),  // the longest name
  mission("drive", drive, startDrive, stopDrive).range(0.0f, 10.0f).unit("m").progressMax(2.0f),
  mission("home", home, startHome, stopDrive)
  CASE);

// Channel ids are one byte: at HUBWIRE_MAX_CHANNELS=254, 255 channels must fail, and 256 (which
// would wrap a count to 0) and 300 as well. MANY_n(p): 2^n channels named p + n binary digits.
#if HUBWIRE_CASE >= 21 && HUBWIRE_CASE <= 23
#define ONE(name) expose(#name, level)
#define MANY_1(p) ONE(p##0), ONE(p##1)
#define MANY_2(p) MANY_1(p##0), MANY_1(p##1)
#define MANY_3(p) MANY_2(p##0), MANY_2(p##1)
#define MANY_4(p) MANY_3(p##0), MANY_3(p##1)
#define MANY_5(p) MANY_4(p##0), MANY_4(p##1)
#define MANY_6(p) MANY_5(p##0), MANY_5(p##1)
#define MANY_7(p) MANY_6(p##0), MANY_6(p##1)
#define MANY_8(p) MANY_7(p##0), MANY_7(p##1)
#if HUBWIRE_CASE == 21
HUBWIRE_CHANNELS(many, "many", MANY_7(a), MANY_6(b), MANY_5(c), MANY_4(d), MANY_3(e), MANY_2(f), MANY_1(g), ONE(h));
#elif HUBWIRE_CASE == 22
HUBWIRE_CHANNELS(many, "many", MANY_8(a));
#else
HUBWIRE_CHANNELS(many, "many", MANY_8(a), MANY_5(b), MANY_3(c), MANY_2(d));
#endif
#endif

// Tables are used: a sketch hands them to begin().
bool start(Session& d) {
#if HUBWIRE_CASE >= 21 && HUBWIRE_CASE <= 23
  d.begin(many);
#endif
  return d.begin(channels);
}
