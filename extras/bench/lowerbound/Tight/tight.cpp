// Tight device session: see tight.h. One raw frame buffer for both directions.
// All state lives in one struct reached through a pointer register (ldd/std with displacement,
// 2 bytes per access instead of lds/sts with 4).
#include "tight.h"

#include <string.h>
#include <util/crc16.h>

#define TW_NOINLINE __attribute__((noinline))

namespace {

enum : uint8_t {
  M_HELLO = '*', M_BEAT = 'H', M_CHUNK = 'J', M_REQ = 'R', M_RESP = 'r', M_CTRL = 'C',
  M_ACK = 0x07, M_NAK = 0x15, M_EVENT = '!', M_SUB = 'S', M_SAMPLE = 'D'
};
enum : uint8_t {
  E_OK = 0, E_TYPE = 1, E_CHANNEL, E_LENGTH, E_RANGE, E_NOT_WRITABLE, E_NOT_READABLE,
  E_NOT_STREAMABLE, E_BUSY, E_OFFSET, E_NOT_LINKED, E_VALUE, E_REJECTED
};

const uint8_t kBufSize = TW_MAX_PAYLOAD + 5;

struct Ev { uint8_t id, len, data[TW_EVENT_MAX]; };
struct Sub { uint8_t id, seq; uint16_t interval, start, last; };

struct St {
  // Receiver.
  uint8_t rxLen, rxLeft, rxStarted, rxOverflow, rxZero;
  // Session.
  uint8_t linked, hubKnown, nonceDrawn, beatSent, peerMax;
  uint16_t lostAfter, lastRx, lastSent, lastByte, beatCounter;
  // Duplicate suppression: last hub transaction; code of the control's answer (0 = ACK).
  uint8_t txnValid, txnCtrl, txnSeq, txnId, txnCode;
  // Events.
  uint8_t evHead, evCount, evSeq, evInFlight;
  uint16_t evSentAt;
  uint16_t cnt[3];  // crc, overflow, dropped: the heartbeat's order
  uint8_t nonce[4], hubNonce[4];
  uint8_t buf[kBufSize];  // raw frame: type seq id payload crc
  Sub subs[TW_HAS_STREAMS ? TW_MAX_STREAMS : 1];
  Ev evq[TW_EVENT_QUEUE];
};
enum { C_CRC, C_OVF, C_DROP };

St st;
TwChannel ch;  // the channel being handled, copied from flash

// The state's address in a pointer register, hidden from the optimiser so that it keeps it there.
inline __attribute__((always_inline)) St* S() {
  St* p = &st;

  return p;
}
#define pl (s->buf + 3)

uint32_t bootCounter __attribute__((section(".noinit")));

inline uint16_t now16() { return (uint16_t)millis(); }

TW_NOINLINE void put16(uint8_t* p, uint16_t v) { memcpy(p, &v, 2); }
inline uint16_t get16(const uint8_t* p) { uint16_t v; memcpy(&v, p, 2); return v; }

// CRC-16/CCITT-FALSE of the first n bytes of the frame buffer.
TW_NOINLINE uint16_t crc(uint8_t n) {
  uint16_t c = 0xFFFF;
  for (const uint8_t* p = st.buf; n; --n) c = _crc_xmodem_update(c, *p++);
  return c;
}

// Header, CRC, COBS, delimiter. Frames are < 254 bytes: no 0xFF blocks.
TW_NOINLINE void send(uint8_t type, uint8_t seq, uint8_t id, uint8_t len) {
  St* s = S();
  s->buf[0] = type;
  s->buf[1] = seq;
  s->buf[2] = id;
  uint8_t n = len + 3;
  put16(s->buf + n, crc(n));
  n += 2;
  uint8_t* p = s->buf;
  uint8_t* end = p + n;
  for (;;) {
    uint8_t* e = p;
    while (e < end && *e) ++e;
    Serial.write((uint8_t)(e - p + 1));
    while (p < e) Serial.write(*p++);
    if (e >= end) break;
    ++p;
  }
  Serial.write((uint8_t)0);
}

// Answers carry the question's seq and id (still in buf[1], buf[2]).
TW_NOINLINE void reply(uint8_t type, uint8_t len) { send(type, st.buf[1], st.buf[2], len); }
TW_NOINLINE void nak(uint8_t code) {
  st.buf[3] = code;
  reply(M_NAK, 1);
}

TW_NOINLINE void clearSubs() {
#if TW_HAS_STREAMS
  memset(st.subs, 0, sizeof(st.subs));
#endif
}

// The nonce: per-boot counter, the clock (millis and timer 0, i.e. what micros() reads) and the
// hub's nonce, mixed bytewise; never 0.
TW_NOINLINE void drawNonce(const uint8_t* hub) {
  St* s = S();
  uint8_t t = (uint8_t)millis();
  const uint8_t* bb = (const uint8_t*)&bootCounter;
  uint8_t any = 0;
  for (uint8_t i = 0; i < 4; ++i) any |= s->nonce[i] = (uint8_t)(hub[i] ^ bb[i] ^ (t + TCNT0));
  if (!any) s->nonce[0] = 1;
  s->nonceDrawn = 1;
}

const uint8_t kZero4[4] = {0, 0, 0, 0};

TW_NOINLINE void sendHello(uint8_t flags) {
  St* s = S();
  if (!s->nonceDrawn) drawNonce(kZero4);
  pl[0] = 1;
  pl[1] = flags;  // DEVICE (1) | REPLY (2)
  memcpy(pl + 2, s->nonce, 4);
  memcpy_P(pl + 6, twHelloTail, 10);
  send(M_HELLO, 0, 0, 16);
}

// Copies channel id into ch; false if there is none.
TW_NOINLINE bool channel(uint8_t id) {
  if (id == 0 || id > twChannelCount) return false;
  memcpy_P(&ch, &twChannels[id - 1], sizeof(ch));
  return true;
}

void onHello(uint8_t len) {
  St* s = S();
  if (len < 16) {
    ++s->cnt[C_DROP];
    return nak(E_LENGTH);
  }
  // Everything is read before the answer overwrites the buffer.
  uint8_t flags = pl[1];
  if (!s->nonceDrawn) drawNonce(pl + 2);
  if (pl[0] == 1 && !(flags & 1)) {  // another version: answered, not linked
    if (!s->hubKnown || memcmp(pl + 2, s->hubNonce, 4)) {  // a new hub session
      s->hubKnown = 1;
      memcpy(s->hubNonce, pl + 2, 4);
      s->txnValid = 0;
      clearSubs();
    }
    uint16_t max = get16(pl + 6), beat = get16(pl + 8);
    s->peerMax = max > TW_MAX_PAYLOAD ? TW_MAX_PAYLOAD : max < 16 ? 16 : (uint8_t)max;
    const uint16_t kMaxBeat = 65535u / TW_LOST_AFTER;
    s->lostAfter = (beat < 10 ? 10 : beat > kMaxBeat ? kMaxBeat : beat) * TW_LOST_AFTER;
    if (!s->linked) {
      s->linked = 1;
      s->beatSent = 0;
      s->evSentAt = now16() - TW_EVENT_RETRY_MS;  // the head event again at once, same seq
    }
  }
  if (!(flags & 2)) sendHello(3);
}

void loseLink(uint16_t t) {
  St* s = S();
  s->linked = 0;
#if TW_HAS_FAILSAFE
  for (uint8_t id = twChannelCount; id; --id) {
    channel(id);
    if (!ch.failsafe) continue;
    uint8_t v[4];
    memcpy_P(v, ch.failsafe, 4);
    if (ch.data) memcpy(ch.data, v, ch.size & 0x7F);
    if (ch.call) ch.call(v);
  }
#endif
  clearSubs();
  s->lastSent = t;
}

uint8_t onChunk(uint8_t len) {
  St* s = S();
  if (len != 3) return E_LENGTH;
  uint16_t off = get16(pl);
  if (off > twDescLength) return E_OFFSET;
  uint8_t n = s->peerMax - 4;
  if (pl[2] < n) n = pl[2];
  if (twDescLength - off < n) n = twDescLength - off;
  put16(pl + 2, twDescLength);
  memcpy_P(pl + 4, twDescriptor + off, n);
  reply(M_CHUNK, 4 + n);
  return E_OK;
}

uint8_t onRequest(uint8_t len) {
  St* s = S();
  if (!channel(s->buf[2])) return E_CHANNEL;
  if (!(ch.access & TW_R)) return E_NOT_READABLE;
  if (len) return E_LENGTH;
  uint8_t n = ch.size & 0x7F;
  memcpy(pl, ch.data, n);
  reply(M_RESP, n);
  return E_OK;
}

uint8_t control(uint8_t len) {
  St* s = S();
  if (!channel(s->buf[2])) return E_CHANNEL;
  if (!(ch.access & (TW_W | TW_C))) return E_NOT_WRITABLE;
  if (len != (ch.size & 0x7F)) return E_LENGTH;
  if ((ch.size & TW_BOOL) && pl[0] > 1) return E_VALUE;
  if (ch.inRange && !ch.inRange(pl)) return E_RANGE;
  if (ch.data) memcpy(ch.data, pl, len);
  if (ch.call && !ch.call(pl)) return E_REJECTED;
  return E_OK;
}

void answerControl() {
  uint8_t code = st.txnCode;
  if (code) return nak(code);
  reply(M_ACK, 0);
}

uint8_t onSubscribe(uint8_t len) {
  St* s = S();
  uint8_t id = s->buf[2];
  if (!channel(id)) return E_CHANNEL;
#if !TW_HAS_STREAMS
  (void)len;
  return E_NOT_STREAMABLE;
#else
  if (!(ch.access & TW_S)) return E_NOT_STREAMABLE;
  if (len != 2) return E_LENGTH;
  uint16_t iv = get16(pl);
  Sub *slot = nullptr, *free = nullptr;
  for (Sub* x = s->subs; x < s->subs + TW_MAX_STREAMS; ++x) {
    if (x->id == id) slot = x;
    if (!x->id && !free) free = x;
  }
  if (!iv) {
    if (slot) slot->id = 0;
  } else {
    uint16_t t = now16();
    if (!slot) {
      if (!free) return E_BUSY;
      slot = free;
      slot->seq = 0;
      slot->last = t;
    }
    if (iv < TW_MIN_STREAM_MS) iv = TW_MIN_STREAM_MS;
    if (iv > 60000) iv = 60000;
    slot->id = id;
    slot->interval = iv;
    slot->start = t - iv;
  }
  put16(pl, iv);
  reply(M_ACK, 2);
  return E_OK;
#endif
}

void handle(uint8_t len) {
  St* s = S();
  s->lastRx = now16();
  uint8_t type = s->buf[0], seq = s->buf[1], id = s->buf[2];
  switch (type) {
    case M_HELLO:
      return onHello(len);
    case M_BEAT:
      if (!s->linked) sendHello(1);
      return;
    case M_ACK:
    case M_NAK:
      if (s->evInFlight && seq == s->evSeq && id == s->evq[s->evHead].id) {
        s->evInFlight = 0;
        s->evHead = (s->evHead + 1) & (TW_EVENT_QUEUE - 1);
        --s->evCount;
      }
      return;
    case M_CHUNK:
    case M_REQ:
    case M_CTRL:
    case M_SUB:
      break;
    default:
      ++s->cnt[C_DROP];
      return nak(E_TYPE);
  }
  if (!s->linked) return nak(E_NOT_LINKED);
  uint8_t ctrl = type == M_CTRL;
  if (ctrl && s->txnValid && s->txnCtrl && seq == s->txnSeq && id == s->txnId) return answerControl();
  s->txnValid = 1;
  s->txnCtrl = ctrl;
  s->txnSeq = seq;
  s->txnId = id;
  uint8_t code;
  if (type == M_CHUNK) code = onChunk(len);
  else if (type == M_REQ) code = onRequest(len);
  else if (type == M_SUB) code = onSubscribe(len);
  else {
    s->txnCode = code = control(len);
    if (!code) reply(M_ACK, 0);
  }
  if (code) nak(code);
}

void rxReset(St* s) {
  s->rxLen = s->rxLeft = s->rxStarted = s->rxOverflow = s->rxZero = 0;
}

void rxPut(St* s, uint8_t b) {
  uint8_t n = s->rxLen;
  if (n >= kBufSize) s->rxOverflow = 1;
  else {
    s->buf[n] = b;
    s->rxLen = n + 1;
  }
}

void rxByte(uint8_t b) {
  St* s = S();
  if (b == 0) {
    uint8_t n = s->rxLen;
    uint8_t started = s->rxStarted, ovf = s->rxOverflow, partial = s->rxLeft;
    rxReset(s);
    if (!started) return;
    uint8_t which = C_OVF;
    if (!ovf) {
      which = C_DROP;
      if (!partial && n >= 5) {
        n -= 2;
        if (crc(n) == get16(s->buf + n)) return handle(n - 3);
        which = C_CRC;
      }
    }
    ++s->cnt[which];
    return;
  }
  s->rxStarted = 1;
  if (s->rxOverflow) return;
  if (s->rxLeft == 0) {
    if (s->rxZero) rxPut(s, 0);
    s->rxLeft = b - 1;
    s->rxZero = b != 0xFF;
  } else {
    rxPut(s, b);
    --s->rxLeft;
  }
}

void sendSamples(uint16_t t) {
#if !TW_HAS_STREAMS
  (void)t;
  return;
#endif
  St* s = S();
  for (Sub* x = s->subs; x < s->subs + TW_MAX_STREAMS; ++x) {
    if (!x->id || (uint16_t)(t - x->start) < x->interval) continue;
    channel(x->id);
    uint8_t n = ch.size & 0x7F;
    if (Serial.availableForWrite() < n + 2 + 7) continue;  // try again next update
    put16(pl, t - x->last);
    memcpy(pl + 2, ch.data, n);
    send(M_SAMPLE, x->seq++, x->id, n + 2);
    x->last = t;
    x->start += x->interval;
    if ((uint16_t)(t - x->start) >= x->interval) x->start = t;
  }
}

}  // namespace

void twBegin() {
  ++bootCounter;
  st.peerMax = TW_MAX_PAYLOAD;
  st.lastSent = now16();  // first announcement one interval after boot
}

bool twEmit(uint8_t id, const void* v, uint8_t n) {
  St* s = S();
  if (s->evCount >= TW_EVENT_QUEUE) return false;
  Ev* e = &s->evq[(s->evHead + s->evCount) & (TW_EVENT_QUEUE - 1)];
  e->id = id;
  e->len = n;
  memcpy(e->data, v, n);
  ++s->evCount;
  return true;
}

namespace {
// Split only so that a -fno-inline-functions-called-once build can attribute bytes.
uint8_t rxPoll() {
  uint8_t i = 0;
  for (; i < 128; ++i) {
    int c = Serial.read();
    if (c < 0) break;
    rxByte((uint8_t)c);
  }
  return i;
}

void sendBeat(uint16_t t) {
  St* s = S();
  uint16_t b = ++s->beatCounter;
  put16(pl, b);
  put16(pl + 2, s->beatSent ? (uint16_t)(t - s->lastSent) : 0);
  memcpy(pl + 4, s->cnt, 6);
  send(M_BEAT, (uint8_t)b, 0, 10);
  s->lastSent = t;
  s->beatSent = 1;
}

void sendEvent(uint16_t t) {
  St* s = S();
  Ev* e = &s->evq[s->evHead];
  if (!s->evInFlight) {
    ++s->evSeq;
    s->evInFlight = 1;
  }
  memcpy(pl, e->data, e->len);
  send(M_EVENT, s->evSeq, e->id, e->len);
  s->evSentAt = t;
}
}  // namespace

void twUpdate() {
  St* s = S();
  uint8_t got = rxPoll();
  uint16_t t = now16();
  if (got) s->lastByte = t;
  if (s->linked && (uint16_t)(t - s->lastRx) >= s->lostAfter) loseLink(t);
  if (s->rxStarted) {  // our own frames wait for a half-received one, unless it stalled
    if ((uint16_t)(t - s->lastByte) < 50) return;
    rxReset(s);
    ++s->cnt[C_DROP];
  }
  if (!s->linked) {
    if ((uint16_t)(t - s->lastSent) >= TW_ANNOUNCE_MS) {
      s->lastSent = t;
      sendHello(1);
    }
    return;
  }
  if (!s->beatSent || (uint16_t)(t - s->lastSent) >= TW_HEARTBEAT_MS) sendBeat(t);
  if (s->evCount && (!s->evInFlight || (uint16_t)(t - s->evSentAt) >= TW_EVENT_RETRY_MS)) sendEvent(t);
  sendSamples(t);
}
