"""How the scale benchmark turns interleaved frame times into a ratio to its base frame:
paired round by round, so a machine whose speed changes during the run, or a burst that
slows one variant's block, does not show up in the ratio (the timings are the
benchmark's business; this checks its arithmetic)."""

from __future__ import annotations

import statistics

import pytest

from mirrorlab.benchmarks.scale import Variant, interleave, paired_ratio

SPEEDS = [1.0, 1.0, 2.0, 2.0, 4.0, 4.0]
"""How many times slower than at its fastest the machine is in each round."""


def scripted_frames(cost: float, bursts: frozenset[int] = frozenset()):
    """A frame function as :func:`interleave` calls it: frames of ``cost`` ms times the
    round's :data:`SPEEDS`, three times slower again in the rounds of ``bursts`` (its first
    call is the warm-up)."""
    calls = [0]

    def frames(count: int) -> list[float]:
        timed_round = calls[0] - 1
        calls[0] += 1
        slow = SPEEDS[max(timed_round, 0)] * (3.0 if timed_round in bursts else 1.0)
        return [cost * slow * (1 + 0.001 * i) for i in range(count)]

    return frames


def test_rounds_are_kept_apart_and_every_variant_gets_its_frames():
    variants = [
        Variant(name, scripted_frames(cost))
        for name, cost in (("base", 1.0), ("double", 2.0), ("same", 1.0))
    ]
    interleave(variants, frames=15, warmup=2, block=5)
    for variant in variants:
        assert [len(block) for block in variant.blocks] == [5, 5, 5]
        assert len(variant.samples) == 15


@pytest.mark.parametrize("factor", [1.0, 1.1, 2.0])
def test_a_ratio_paired_by_round_follows_the_machine_s_speed(factor):
    base = Variant("base", scripted_frames(1.0))
    other = Variant("other", scripted_frames(factor))
    interleave([base, other], frames=30, warmup=5, block=5)
    assert paired_ratio(other.blocks, base.blocks) == pytest.approx(factor, rel=1e-12)
    assert paired_ratio(base.blocks, base.blocks) == 1.0


def test_bursts_in_a_minority_of_rounds_leave_the_paired_ratio_alone():
    base = Variant("base", scripted_frames(1.0))
    other = Variant("other", scripted_frames(1.1, bursts=frozenset({1, 4})))
    interleave([base, other], frames=30, warmup=5, block=5)
    assert paired_ratio(other.blocks, base.blocks) == pytest.approx(1.1, rel=1e-12)
    # the ratio of the two runs' medians takes them in: about 1.38x
    pooled = statistics.median(other.samples) / statistics.median(base.samples)
    assert pooled > 1.3
