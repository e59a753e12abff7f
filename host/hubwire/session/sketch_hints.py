"""What the hub hears that points at the two commonest sketch mistakes.

- ``delay()`` in ``loop()``: the device calls ``hub.update()`` seconds apart, so its heartbeats and
  answers come that far apart. :class:`LoopWatch` notices (the device's own heartbeat interval, or
  silences the hub heard that ended with the device speaking again, not starting again) and adds a
  hint to a lost link or an unanswered request.
- ``Serial.println`` debugging on the Hubwire line: the frame decoder finds the text among the
  bytes it discards; :class:`PrintedText` says so in the log, at most once every
  :data:`SAY_EVERY` seconds, because each line also spoils the frame it runs into."""
from __future__ import annotations

import logging
import time
from typing import List, Optional, Tuple

from ..diagnose import blocked_loop_hint
from ..text import clip
from ..wire import messages as m
from ..wire.frame import FrameDecoder

__all__ = ["LoopWatch", "PrintedText", "SAY_EVERY", "QUIET_WINDOW"]

log = logging.getLogger("hubwire")

#: seconds between two log lines about printed text (the lines in between are counted)
SAY_EVERY = 30.0
#: silences older than this (seconds) no longer count as signs of a blocked loop()
QUIET_WINDOW = 15.0


class LoopWatch:
    """Silences of the device that ended with it speaking again (a few, within QUIET_WINDOW)."""

    def __init__(self) -> None:
        #: (when, seconds) of the recent silences that ended with the device speaking again
        self.gaps: List[Tuple[float, float]] = []

    def heard(self, now: float, last_rx: float, beat_ms: int) -> None:
        """The device spoke at ``now``, last before at ``last_rx`` (0: never)."""
        if last_rx and now - last_rx > 2 * beat_ms / 1000.0:
            self.gaps = [g for g in self.gaps if now - g[0] < QUIET_WINDOW][-3:] + [(now, now - last_rx)]

    def started(self) -> None:
        """The device (re)started: a silence that ended so was a reset, not a blocked loop()."""
        self.gaps.clear()

    def gap_ms(self, hb: Optional[m.Heartbeat], beat_ms: int) -> Optional[int]:
        """How far apart the device's heartbeats come when that shows a blocked loop(): measured by
        the device in its latest heartbeat ``hb``, or a recent silence; else None."""
        if hb is not None and hb.since_ms >= 3 * beat_ms:
            return int(hb.since_ms)
        now = time.monotonic()
        long = [g for t, g in self.gaps if now - t < QUIET_WINDOW and g * 1000 >= 3 * beat_ms]
        return round(long[-1] * 1000) if long else None

    def hint(self, hb: Optional[m.Heartbeat], beat_ms: int) -> str:
        """:func:`hubwire.diagnose.blocked_loop_hint` for this device, empty when nothing shows it."""
        gap = self.gap_ms(hb, beat_ms)
        return blocked_loop_hint(gap, beat_ms, silent=hb is None or gap != hb.since_ms)


class PrintedText:
    def __init__(self, url: str) -> None:
        self.url = url
        self.seen = 0  # text lines the decoder had found when last looked at
        self._unsaid = 0  # lines printed while linked and not logged yet
        self._said_at: float = -SAY_EVERY

    def check(self, decoder: FrameDecoder, linked: bool, now: float) -> None:
        """Log what the board printed since the last look, if it is time (linked only: before that
        no_answer_message describes what the port said)."""
        new, self.seen = decoder.text_lines - self.seen, decoder.text_lines
        self._unsaid = self._unsaid + new if linked else 0
        if not self._unsaid or now - self._said_at < SAY_EVERY:
            return
        more, self._unsaid, self._said_at = self._unsaid - 1, 0, now
        log.warning("hubwire: the board on %s printed: %s%s (text on the Hubwire line spoils the frame after "
                    "it: print on another port, or not at all)", self.url, clip(decoder.text[-1], 90),
                    f" and {more} more line{'s' if more != 1 else ''}" if more > 0 else "")

    @staticmethod
    def recent(decoder: FrameDecoder) -> Tuple[int, List[str]]:
        """How many lines the board printed in all, and the latest of them (newest last)."""
        return decoder.text_lines, list(decoder.text)
