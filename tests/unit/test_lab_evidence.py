"""Lab evidence is bounded by design: events that share an unchanged state snapshot are
saved with one copy of it and read back as before, so evidence.json grows with the states
judged, not with the number of calls; the tracker counts each frame's bytes."""

from __future__ import annotations

import json

from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.state import Tracker


def test_events_that_share_a_state_are_saved_with_one_copy(tmp_path):
    tracker = Tracker()
    tracker.begin_frame()
    state = tracker.snapshot()
    assert tracker.snapshot() is state  # unchanged state: the same object
    for _ in range(500):
        tracker.event("draw", who="primitive", state=tracker.snapshot())
    tracker.set_enabled(0x0B71, True)  # GL_DEPTH_TEST: a new state
    tracker.event("draw", who="primitive", state=tracker.snapshot())
    evidence = Evidence("lab20", frames=tracker.frames)
    evidence.save(tmp_path)
    saved = json.loads((tmp_path / "evidence.json").read_text())
    assert len(saved["states"]) == 2
    loaded = Evidence.load(tmp_path)
    assert loaded.frames == json.loads(json.dumps(tracker.frames))
    assert loaded.frames[0]["events"][0]["state"] is loaded.frames[0]["events"][1]["state"]


def test_frame_bytes_grow_with_events_but_count_a_shared_state_once():
    tracker = Tracker()
    tracker.begin_frame()
    tracker.event("draw", state=tracker.snapshot())
    first = tracker.frame_bytes
    tracker.event("draw", state=tracker.snapshot())
    second = tracker.frame_bytes - first
    assert 0 < second < first / 2
    tracker.begin_frame()
    assert tracker.frame_bytes == 0


def test_a_malformed_state_reference_reads_as_no_state(tmp_path):
    plain = {
        "lab": "lab20",
        "frames": [
            {
                "events": [
                    {"kind": "draw", "state": {"$state": 7}},
                    {"kind": "draw", "state": {"$state": "x"}},
                ]
            }
        ],
        "states": [{"viewport": 1}],
    }
    (tmp_path / "evidence.json").write_text(json.dumps(plain))
    Evidence("lab20").save(tmp_path / "empty")
    (tmp_path / "arrays.npz").write_bytes((tmp_path / "empty" / "arrays.npz").read_bytes())
    loaded = Evidence.load(tmp_path)
    assert [e["state"] for e in loaded.frames[0]["events"]] == [{}, {}]
