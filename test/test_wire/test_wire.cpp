// The wire layer against the golden vectors in test/vectors (shared with the Python suite), plus a
// resync test: random valid frames among garbage and corrupted frames.
#include <gtest/gtest.h>

#include <dirent.h>

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <set>

#include "fakes.h"
#include "hubwire/wire/messages.h"
#include "hubwire/wire/bytes.h"
#include "hubwire/wire/cobs.h"
#include "hubwire/wire/crc16.h"
#include "hubwire/wire/frame.h"
#include "hubwire/wire/values.h"

using namespace hubwire;
using namespace hubwire::test;
using nlohmann::json;

namespace {

std::set<std::string> consumed;

json load(const std::string& file) {
  std::ifstream in(std::string(HUBWIRE_VECTORS_DIR) + "/" + file);
  EXPECT_TRUE(in.good()) << file;
  json j = json::parse(in);
  EXPECT_FALSE(j["vectors"].empty()) << file;
  consumed.insert(file);
  return j["vectors"];
}

std::string hexOf(const Bytes& b) { return toHex(b.data(), b.size()); }

// A scalar's meaning as a double, and a double stored as a scalar: how the vectors' JSON values
// are compared with wire bytes (the device itself never converts through double).
template <typename T>
double readAs(const uint8_t* p) {
  T v;
  memcpy(&v, p, sizeof(T));
  return (double)v;
}
double scalarAsDouble(TypeCode t, const uint8_t* p) {
  switch (t) {
    case kBool:
    case kU8: return p[0];
    case kI8: return (int8_t)p[0];
    case kU16: return readAs<uint16_t>(p);
    case kI16: return readAs<int16_t>(p);
    case kU32: return readAs<uint32_t>(p);
    case kI32: return readAs<int32_t>(p);
    case kF32: return readAs<float>(p);
    case kF64: return readAs<double>(p);
    default: return 0;
  }
}
template <typename T>
void writeAs(double d, void* mem) {
  T v = (T)d;
  memcpy(mem, &v, sizeof(T));
}
void storeScalar(TypeCode t, double v, void* mem) {
  switch (t) {
    case kBool: *(uint8_t*)mem = v != 0; break;
    case kU8: writeAs<uint8_t>(v, mem); break;
    case kI8: writeAs<int8_t>(v, mem); break;
    case kU16: writeAs<uint16_t>(v, mem); break;
    case kI16: writeAs<int16_t>(v, mem); break;
    case kF32: writeAs<float>(v, mem); break;
    case kF64: writeAs<double>(v, mem); break;
    default: break;
  }
}

TEST(Vectors, Crc) {
  for (auto& v : load("crc.json")) {
    Bytes d = hex(v["data"]);
    EXPECT_EQ(crc16(d.data(), d.size()), v["crc"].get<int>()) << v["name"];
  }
  const uint8_t check[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(crc16(check, 9), 0x29B1);
}

TEST(Vectors, Cobs) {
  for (auto& v : load("cobs.json")) {
    Bytes dec = hex(v["decoded"]), enc = hex(v["encoded"]);
    Bytes out(cobsMaxEncoded(dec.size()));
    out.resize(cobsEncode(dec.data(), dec.size(), out.data()));
    EXPECT_EQ(hexOf(out), hexOf(enc)) << v["name"];
    Bytes back(dec.size() + 1);
    size_t n = 0;
    ASSERT_TRUE(cobsDecode(enc.data(), enc.size(), back.data(), back.size(), &n)) << v["name"];
    back.resize(n);
    EXPECT_EQ(hexOf(back), hexOf(dec)) << v["name"];
  }
}

void checkMessage(const json& m, uint8_t type, const Bytes& p) {
  std::string kind = m["kind"];
  auto u16 = [&](size_t o) { return (int)loadU16(&p[o]); };
  if (kind == "hello") {
    ASSERT_EQ(type, kMsgHello);
    ASSERT_GE(p.size(), kHelloSize);
    EXPECT_EQ(p[0], m["version"].get<int>());
    EXPECT_EQ(p[1], m["flags"].get<int>());
    EXPECT_EQ(loadU32(&p[2]), m["nonce"].get<uint32_t>());
    EXPECT_EQ(u16(6), m["max_payload"].get<int>());
    EXPECT_EQ(u16(8), m["heartbeat_ms"].get<int>());
    EXPECT_EQ(loadU32(&p[10]), m["descriptor_hash"].get<uint32_t>());
    EXPECT_EQ(u16(14), m["descriptor_length"].get<int>());
    // The descriptor digest: bytes 16..31 when all of them are there, else none.
    if (m.contains("descriptor_digest")) {
      ASSERT_GE(p.size(), kHelloDigestEnd);
      EXPECT_EQ(toHex(&p[kHelloSize], kDigestSize), m["descriptor_digest"].get<std::string>());
    } else {
      EXPECT_LT(p.size(), kHelloDigestEnd);
    }
  } else if (kind == "heartbeat") {
    ASSERT_EQ(type, kMsgHeartbeat);
    ASSERT_EQ(p.size(), kHeartbeatSize);
    EXPECT_EQ(u16(0), m["counter"].get<int>());
    EXPECT_EQ(u16(2), m["since_ms"].get<int>());
    EXPECT_EQ(u16(4), m["crc"].get<int>());
    EXPECT_EQ(u16(6), m["overflow"].get<int>());
    EXPECT_EQ(u16(8), m["dropped"].get<int>());
  } else if (kind == "chunk_request") {
    ASSERT_EQ(type, kMsgChunk);
    ASSERT_EQ(p.size(), kChunkRequestSize);
    EXPECT_EQ(u16(0), m["offset"].get<int>());
    EXPECT_EQ(p[2], m["want"].get<int>());
  } else if (kind == "chunk") {
    ASSERT_EQ(type, kMsgChunk);
    EXPECT_EQ(u16(0), m["offset"].get<int>());
    EXPECT_EQ(u16(2), m["total"].get<int>());
    EXPECT_EQ(toHex(p.data() + 4, p.size() - 4), m["data"].get<std::string>());
  } else if (kind == "subscribe") {
    ASSERT_EQ(type, kMsgSubscribe);
    EXPECT_EQ(u16(0), m["interval_ms"].get<int>());
  } else if (kind == "ack") {
    ASSERT_EQ(type, kMsgAck);
    if (m.contains("granted_ms")) {
      ASSERT_EQ(p.size(), 2u);
      EXPECT_EQ(u16(0), m["granted_ms"].get<int>());
    } else {
      EXPECT_TRUE(p.empty());
    }
  } else if (kind == "nak") {
    ASSERT_EQ(type, kMsgNak);
    ASSERT_EQ(p.size(), 1u);
    EXPECT_EQ(p[0], m["code"].get<int>());
  } else if (kind == "sample") {
    ASSERT_EQ(type, kMsgSample);
    EXPECT_EQ(u16(0), m["since_ms"].get<int>());
    EXPECT_EQ(toHex(p.data() + 2, p.size() - 2), m["value"].get<std::string>());
  } else {
    static const std::map<std::string, uint8_t> plain = {
        {"request", kMsgRequest}, {"response", kMsgResponse}, {"control", kMsgControl}, {"event", kMsgEvent}};
    ASSERT_TRUE(plain.count(kind)) << "unknown message kind " << kind;
    EXPECT_EQ(type, plain.at(kind));
    EXPECT_EQ(hexOf(p), m["value"].get<std::string>());
  }
}

TEST(Frame, WireSizeOfAByteLongPayloadAsTheGeneralOne) {
  for (unsigned len = 0; len <= 255; ++len)
    EXPECT_EQ(FrameWriter::wireSize8((uint8_t)len), FrameWriter::wireSize(len)) << len;
}

TEST(Vectors, Frames) {
  std::set<std::string> kinds;
  for (auto& v : load("frames.json")) {
    Bytes payload = hex(v["payload"]);
    uint8_t type = v["type"], seq = v["seq"], id = v["id"];
    // Built with the device's writer, byte for byte.
    uint8_t buf[HUBWIRE_SEND_FRAME_SIZE(255)];
    FrameWriter w(buf);
    memcpy(w.payload(), payload.data(), payload.size());
    FakeStream s;
    FakeClock c;
    Port p(s, c);
    w.send(p, type, seq, id, (uint8_t)payload.size());
    EXPECT_EQ(hexOf(s.out), v["wire"].get<std::string>()) << v["name"];
    EXPECT_LE(s.out.size(), FrameWriter::wireSize(payload.size()));
    if (payload.size() <= 32) {  // the writer that leaves out blocks without an implied zero
      uint8_t small[HUBWIRE_SEND_FRAME_SIZE(32)];
      BasicFrameWriter<32> sw(small);
      memcpy(sw.payload(), payload.data(), payload.size());
      FakeStream ss;
      Port sp(ss, c);
      sw.send(sp, type, seq, id, (uint8_t)payload.size());
      EXPECT_EQ(hexOf(ss.out), v["wire"].get<std::string>()) << v["name"];
    }
    Bytes whole(FrameWriter::wireSize(payload.size()));
    whole.resize(encodeFrame(type, seq, id, payload.data(), (uint8_t)payload.size(), whole.data()));
    EXPECT_EQ(hexOf(whole), v["wire"].get<std::string>()) << v["name"];
    // Parsed by the receiver into exactly this frame.
    uint8_t rxBuf[HUBWIRE_RAW_FRAME_SIZE(255)];
    FrameReceiver rx(rxBuf, sizeof(rxBuf));
    int frames = 0;
    for (uint8_t b : hex(v["wire"])) {
      if (!rx.feed(b)) continue;
      ++frames;
      const Frame& f = rx.frame();
      EXPECT_EQ(f.type, type);
      EXPECT_EQ(f.seq, seq);
      EXPECT_EQ(f.id, id);
      EXPECT_EQ(toHex(f.payload, f.len), v["payload"].get<std::string>()) << v["name"];
    }
    EXPECT_EQ(frames, 1) << v["name"];
    checkMessage(v["message"], type, payload);
    kinds.insert(v["message"]["kind"].get<std::string>());
  }
  EXPECT_EQ(kinds.size(), 12u) << "every message kind needs a vector";
}

// Feeds a vector's input to a decoder with an index of Index over cap bytes and checks its frames
// and counters.
template <typename Index>
void checkStream(const json& v, Index cap) {
  std::vector<uint8_t> buf(cap);
  FrameDecoderOf<Index> rx{};
  json got = json::array();
  for (uint8_t b : hex(v["input"])) {
    if (!rx.feed(b, buf.data(), cap)) continue;
    const Frame& f = rx.frame(buf.data());
    got.push_back({{"type", f.type}, {"seq", f.seq}, {"id", f.id}, {"payload", toHex(f.payload, f.len)}});
  }
  EXPECT_EQ(got, v["frames"]) << v["name"];
  EXPECT_EQ(rx.counters.crc, v["counters"]["crc"].get<int>()) << v["name"];
  EXPECT_EQ(rx.counters.overflow, v["counters"]["overflow"].get<int>()) << v["name"];
  EXPECT_EQ(rx.counters.dropped, v["counters"]["dropped"].get<int>()) << v["name"];
}

TEST(Vectors, Streams) {
  for (auto& v : load("streams.json")) {
    uint16_t cap = HUBWIRE_RAW_FRAME_SIZE(v["max_payload"].get<int>());
    std::vector<uint8_t> buf(cap);
    FrameReceiver rx(buf.data(), cap);
    json got = json::array();
    for (uint8_t b : hex(v["input"])) {
      if (!rx.feed(b)) continue;
      const Frame& f = rx.frame();
      got.push_back({{"type", f.type}, {"seq", f.seq}, {"id", f.id}, {"payload", toHex(f.payload, f.len)}});
    }
    EXPECT_EQ(got, v["frames"]) << v["name"];
    EXPECT_EQ(rx.counters.crc, v["counters"]["crc"].get<int>()) << v["name"];
    EXPECT_EQ(rx.counters.overflow, v["counters"]["overflow"].get<int>()) << v["name"];
    EXPECT_EQ(rx.counters.dropped, v["counters"]["dropped"].get<int>()) << v["name"];
    // The session's decoder counts in one byte where its buffer allows (session.h): the same.
    if (cap <= 255) checkStream<uint8_t>(v, (uint8_t)cap);
    checkStream<uint16_t>(v, cap);
  }
}

// The largest buffer a one-byte index covers, 255 bytes (HUBWIRE_MAX_PAYLOAD 250): a frame that
// fills it is taken, one byte more overflows, and the next frame is taken again, with either index.
template <typename Index>
void checkFullBuffer() {
  const Index cap = HUBWIRE_RAW_FRAME_SIZE(250);
  uint8_t buf[HUBWIRE_RAW_FRAME_SIZE(250)];
  FrameDecoderOf<Index> rx{};
  for (uint8_t len : {250, 251, 0, 250}) {
    Bytes payload(len, 0x5A);
    if (len) payload[len / 2] = 0;  // two COBS blocks
    uint8_t wire[300];
    size_t n = encodeFrame('H', 1, 2, payload.data(), len, wire);
    bool got = false;
    for (size_t i = 0; i < n; ++i) got = rx.feed(wire[i], buf, cap);
    EXPECT_EQ(got, len <= 250) << (int)len;
    if (got) {
      EXPECT_EQ(rx.frame(buf).len, len);
      EXPECT_EQ(toHex(rx.frame(buf).payload, len), toHex(payload.data(), len));
    }
  }
  EXPECT_EQ(rx.counters.overflow, 1);
  EXPECT_EQ(rx.counters.crc + rx.counters.dropped, 0);
}

TEST(Receiver, FullBufferWithEitherIndex) {
  checkFullBuffer<uint8_t>();
  checkFullBuffer<uint16_t>();
}

// ---- typed values ----

TypeCode codeOf(const std::string& t) {
  for (uint8_t c = 0; c < kTypeCount; ++c) {
    Text n = typeName((TypeCode)c);
    if (t == n.ptr) return (TypeCode)c;
  }
  ADD_FAILURE() << "unknown type " << t;
  return kVoid;
}

struct TypeUnderTest {
  ValueType type;
  std::string layout;  // keeps the compiled layout alive: type code and count a field, then kVoid
};

TypeUnderTest typeFrom(const json& t) {
  TypeUnderTest out;
  out.type.code = codeOf(t["t"]);
  out.type.count = t.value("c", 0);
  if (t.contains("vc")) {  // a List: count is its capacity
    out.type.code = listOf(out.type.code);
    out.type.count = t["vc"].get<uint8_t>();
  }
  if (out.type.code == kStruct) {
    for (auto& f : t["f"]) {
      out.layout += (char)codeOf(f["t"]);
      out.layout += (char)f.value("c", 1);
    }
    out.layout += (char)kVoid;
  }
  return out;
}

void putScalar(TypeCode c, const json& v, Bytes& out) {
  uint8_t tmp[8];
  double d = v.is_boolean() ? (v.get<bool>() ? 1 : 0) : v.get<double>();
  if (c == kU32) {
    uint32_t x = v.get<uint32_t>();
    memcpy(tmp, &x, 4);
  } else if (c == kI32) {
    int32_t x = v.get<int32_t>();
    memcpy(tmp, &x, 4);
  } else {
    storeScalar(c, d, tmp);
  }
  out.insert(out.end(), tmp, tmp + scalarSize(c));
}

// Encodes a JSON value the way the hub does, using the core's scalar store, for comparison.
Bytes encodeJson(const json& type, const json& value) {
  Bytes out;
  TypeCode c = codeOf(type["t"]);
  if (c == kStr) {
    std::string s = value;
    out.push_back((uint8_t)s.size());
    out.insert(out.end(), s.begin(), s.end());
  } else if (c == kStruct) {
    for (auto& f : type["f"]) {
      json fv = value.is_object() ? value[f["n"].get<std::string>()] : json();
      Bytes part = encodeJson(f, fv);
      out.insert(out.end(), part.begin(), part.end());
    }
  } else if (type.contains("vc")) {
    out.push_back((uint8_t)value.size());
    for (auto& e : value) putScalar(c, e, out);
  } else if (type.contains("c")) {
    for (auto& e : value) putScalar(c, e, out);
  } else {
    putScalar(c, value, out);
  }
  return out;
}

bool sameNumber(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

TEST(Vectors, Values) {
  for (auto& v : load("values.json")) {
    TypeUnderTest t = typeFrom(v["type"]);
    t.type.layout = t.layout.c_str();
    Bytes wire = hex(v["hex"]);
    EXPECT_EQ(t.type.check(wire.data(), (uint16_t)wire.size()), kOk) << v["name"];
    if (t.type.code != kStr && !isListCode(t.type.code)) {
      EXPECT_EQ(t.type.wireSize(), wire.size()) << v["name"];
    }
    if (isListCode(t.type.code)) {  // the most it takes: a full list
      EXPECT_GE(t.type.wireSize(), wire.size()) << v["name"];
      EXPECT_EQ(t.type.wireSize(), 1u + t.type.count * scalarSize(elementOf(t.type.code))) << v["name"];
    }
    // memory -> wire -> memory round trip through the core's converters
    std::vector<uint8_t> mem(t.type.memSize() + 1, 0xEE);
    t.type.fromWire(wire.data(), (uint16_t)wire.size(), mem.data());
    Bytes again(t.type.wireSize());
    again.resize(t.type.toWire(mem.data(), again.data()));
    EXPECT_EQ(hexOf(again), v["hex"].get<std::string>()) << v["name"];
    // the JSON meaning: scalars and arrays compared element by element
    if (t.type.code == kVoid) {
      EXPECT_TRUE(wire.empty() && v["value"].is_null()) << v["name"];
    } else if (t.type.code == kStr) {
      EXPECT_EQ(std::string(wire.begin() + 1, wire.end()), v["value"].get<std::string>()) << v["name"];
    } else if (isListCode(t.type.code)) {
      EXPECT_EQ(wire[0], v["value"].size()) << v["name"];
      EXPECT_EQ(hexOf(encodeJson(v["type"], v["value"])), v["hex"].get<std::string>()) << v["name"];
    } else if (t.type.code != kStruct) {
      json vals = t.type.count ? v["value"] : json::array({v["value"]});
      uint8_t size = scalarSize(t.type.code);
      ASSERT_EQ(vals.size() * size, wire.size()) << v["name"];
      for (size_t i = 0; i < vals.size(); ++i) {
        double want = vals[i].is_boolean() ? vals[i].get<bool>() : vals[i].get<double>();
        EXPECT_TRUE(sameNumber(scalarAsDouble(t.type.code, &wire[i * size]), want)) << v["name"] << " [" << i << "]";
      }
    } else {
      EXPECT_EQ(hexOf(encodeJson(v["type"], v["value"])), v["hex"].get<std::string>()) << v["name"];
    }
  }
}

TEST(Vectors, InvalidValues) {
  for (auto& v : load("values_invalid.json")) {
    TypeUnderTest t = typeFrom(v["type"]);
    t.type.layout = t.layout.c_str();
    Bytes wire = hex(v["hex"]);
    ErrorCode want = v["error"] == "BAD_LENGTH" ? kErrBadLength : kErrBadValue;
    EXPECT_EQ(t.type.check(wire.data(), (uint16_t)wire.size()), want) << v["name"];
  }
}

// ---- beyond the vectors ----

TEST(Resync, RecoversEveryValidFrameAmongGarbage) {
  std::mt19937 rng(20261121);
  std::uniform_int_distribution<int> byte(0, 255), len(0, 32), choice(0, 9);
  uint8_t rxBuf[HUBWIRE_RAW_FRAME_SIZE(32)];
  FrameReceiver rx(rxBuf, sizeof(rxBuf));
  Bytes wire;
  std::vector<Bytes> sent;
  for (int i = 0; i < 10000; ++i) {
    Bytes payload(len(rng));
    for (auto& b : payload) b = (uint8_t)byte(rng);
    uint8_t type = (uint8_t)byte(rng), seq = (uint8_t)byte(rng), id = (uint8_t)byte(rng);
    uint8_t enc[300];
    size_t n = encodeFrame(type, seq, id, payload.data(), (uint8_t)payload.size(), enc);
    int what = choice(rng);
    if (what == 0) {  // garbage burst, then a delimiter so it cannot swallow the next frame
      for (int k = len(rng); k >= 0; --k) wire.push_back((uint8_t)byte(rng));
      wire.push_back(0);
    } else if (what == 1) {  // corrupt one non-delimiter byte of a frame: must not be accepted
      size_t at = (size_t)byte(rng) % (n - 1);
      uint8_t flip = (uint8_t)(1 + byte(rng) % 255);
      enc[at] = (uint8_t)(enc[at] ^ flip);
      if (enc[at] == 0) enc[at] = 0x5A;  // keep it one frame
      wire.insert(wire.end(), enc, enc + n);
      wire.push_back(0);  // a corrupted COBS code may have swallowed the delimiter
      continue;
    } else if (what == 2) {  // truncated frame
      wire.insert(wire.end(), enc, enc + n / 2);
      wire.push_back(0);
      continue;
    }
    wire.insert(wire.end(), enc, enc + n);
    Bytes raw = {type, seq, id};
    raw.insert(raw.end(), payload.begin(), payload.end());
    sent.push_back(raw);
  }
  std::vector<Bytes> got;
  for (uint8_t b : wire) {
    if (!rx.feed(b)) continue;
    const Frame& f = rx.frame();
    Bytes raw = {f.type, f.seq, f.id};
    raw.insert(raw.end(), f.payload, f.payload + f.len);
    got.push_back(raw);
  }
  // Every valid frame, in order; a corrupted frame passing CRC-16 would show up as an extra one.
  ASSERT_EQ(got.size(), sent.size());
  EXPECT_TRUE(got == sent);
  EXPECT_GT(rx.counters.crc + rx.counters.dropped, 1000u);
}

TEST(Cobs, RejectsMalformedInput) {
  uint8_t out[8];
  size_t n;
  const uint8_t pointsPast[] = {0x05, 0x01};
  EXPECT_FALSE(cobsDecode(pointsPast, 2, out, sizeof(out), &n));
  const uint8_t zeroInside[] = {0x03, 0x00, 0x01};
  EXPECT_FALSE(cobsDecode(zeroInside, 3, out, sizeof(out), &n));
  const uint8_t tooLong[] = {0x0A, 1, 2, 3, 4, 5, 6, 7, 8, 9};
  EXPECT_FALSE(cobsDecode(tooLong, 10, out, 4, &n));
}

// Runs last (gtest keeps declaration order within a file): every vector file must have been used.
TEST(Vectors, ZZEveryFileIsConsumed) {
  DIR* d = opendir(HUBWIRE_VECTORS_DIR);
  ASSERT_NE(d, nullptr);
  std::set<std::string> files;
  while (dirent* e = readdir(d)) {
    std::string n = e->d_name;
    if (n.size() > 5 && n.substr(n.size() - 5) == ".json") files.insert(n);
  }
  closedir(d);
  EXPECT_EQ(files, consumed) << "a vector file is not consumed by the C++ suite";
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
