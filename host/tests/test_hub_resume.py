"""A hub session resumed after a restart of the hub (session/resume.py, PROTOCOL.md 4.2): what the
seq rules skip until the device has shown what it no longer remembers."""
from __future__ import annotations

from hubwire.session.seqs import SeqRules
from hubwire.wire import messages as m


def free(seq: int, id: int) -> bool:
    return False


def draw_answered(rules: SeqRules, type: int, id: int) -> "int | None":
    """A draw for a message answered at once: nothing of it can come later (seqs.Unanswered)."""
    s = rules.draw(type, id, free)
    if s is not None:
        rules.unanswered.ended((s, id))
        rules.unanswered.answered((s, id))
    return s


def test_resumed_rules_skip_the_kept_event_seqs_and_every_control() -> None:
    rules = SeqRules(4)
    rules.resumed(acked=5, head=9)
    assert rules.draw(m.CONTROL, 3, free) is None, "the device may remember any control: none numbered"
    for _ in range(600):
        s = draw_answered(rules, m.EVENT, 1)
        assert s not in (5, 9, None)
    r = rules.draw(m.REQUEST, 0, free)  # the board id read
    assert r is not None
    rules.other_answered(rules.draws)
    assert rules.controls == {} and rules.draw(m.CONTROL, 3, free) is not None


def test_resumed_head_acked_then_the_next_event_skips_it() -> None:
    rules = SeqRules(0)
    rules.resumed(acked=None, head=7)
    assert rules.events == {7}
    rules.event_ended(7, True)  # the head, re-sent with its seq, acknowledged again
    for _ in range(300):
        assert draw_answered(rules, m.EVENT, 1) not in (7, None)


def test_answer_before_resume_marks_nothing_older() -> None:
    """A read drawn before the resume does not end the controls it marks (only later ones do)."""
    rules = SeqRules(0)
    r = rules.draw(m.REQUEST, 0, free)
    assert r is not None
    drawn = rules.draws
    rules.resumed(acked=None, head=None)
    rules.other_answered(drawn)
    assert len(rules.controls) == 256
