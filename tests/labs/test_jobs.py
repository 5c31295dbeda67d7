"""mirrorlab/jobs.py: every engine gives each key exactly once; a job that raises gives
its error; a worker process that dies mid-job has its job run again elsewhere, neither
lost nor counted twice."""

from __future__ import annotations

import os

import pytest

from mirrorlab.jobs import DaskExecutor, Executor, PoolExecutor, open_executor
from tests.labs import jobfunctions


def outcomes(executor, function, jobs):
    seen = [(o.key, o.value, o.error) for o in executor.run(function, jobs)]
    keys = [key for key, _, _ in seen]
    assert len(keys) == len(set(keys)), f"a key came back twice: {keys}"
    return {key: (value, error) for key, value, error in seen}


@pytest.fixture(scope="module")
def dask_executor():
    with DaskExecutor(2) as executor:
        yield executor


def engines(dask_executor):
    return [Executor(), PoolExecutor(2), dask_executor]


def test_open_executor_picks_the_engine():
    assert type(open_executor(1)) is Executor
    with open_executor(2) as pool:
        assert pool.engine == "pool" and pool.workers == 2
    with pytest.raises(ValueError, match="--engine"):
        open_executor(2, engine="threads")
    with pytest.raises(ValueError, match="--scheduler: cannot reach"):
        DaskExecutor(address="tcp://127.0.0.1:9", connect_timeout="1s")


def test_every_engine_gives_every_key_once(dask_executor):
    jobs = {f"job{i}": (i,) for i in range(12)}
    for executor in engines(dask_executor):
        got = outcomes(executor, jobfunctions.square, jobs)
        assert got == {f"job{i}": (i * i, None) for i in range(12)}, executor.engine


def test_a_job_that_raises_gives_its_error(dask_executor):
    for executor in engines(dask_executor):
        got = outcomes(executor, jobfunctions.fail, {"a": (1,), "b": (2,)})
        assert got["a"][0] is None and "ValueError: no good: 1" in got["a"][1], executor.engine
        assert "no good: 2" in got["b"][1]


def test_pool_runs_a_dead_workers_job_again(tmp_path):
    marker = tmp_path / "died"
    jobs = {"dies": (str(marker), 7), **{f"k{i}": (str(tmp_path / "never"), i) for i in range(4)}}
    (tmp_path / "never").touch()  # the other jobs never die
    got = outcomes(PoolExecutor(2), jobfunctions.die_once, jobs)
    assert marker.exists()
    assert got == {"dies": (7, None), **{f"k{i}": (i, None) for i in range(4)}}


def test_dask_runs_a_dead_workers_job_again(tmp_path, dask_executor):
    marker = tmp_path / "died"
    (tmp_path / "never").touch()
    jobs = {"dies": (str(marker), 7), **{f"k{i}": (str(tmp_path / "never"), i) for i in range(4)}}
    got = outcomes(dask_executor, jobfunctions.die_once, jobs)
    assert marker.exists()
    assert got == {"dies": (7, None), **{f"k{i}": (i, None) for i in range(4)}}


def test_each_job_runs_once_when_nothing_dies(tmp_path, dask_executor):
    for executor in engines(dask_executor):
        folder = tmp_path / executor.engine
        folder.mkdir()
        got = outcomes(
            executor, jobfunctions.count_calls, {f"k{i}": (str(folder), f"k{i}") for i in range(6)}
        )
        assert sorted(got) == [f"k{i}" for i in range(6)]
        assert len(list(folder.iterdir())) == 6


def test_a_pool_keeps_its_workers_from_the_first_run_to_close():
    """The accuracy sweep forks its workers before it opens its OpenGL context and reuses
    them after: every run of one pool is served by the processes started for the first.

    Which process serves a given job is up to the scheduler (a worker that starts late may
    get none of six quick jobs), so the runs are compared with the pool's own process
    list, never with each other. (Under a start method that spawns workers on demand the
    second run may add one; none is ever replaced.)"""
    with PoolExecutor(2) as pool:
        first = {
            o.value for o in pool.run(jobfunctions.process_id, {f"a{i}": (i,) for i in range(6)})
        }
        kept_pool = pool._pool
        assert kept_pool is not None
        started = set(kept_pool._processes)
        again = {
            o.value for o in pool.run(jobfunctions.process_id, {f"b{i}": (i,) for i in range(6)})
        }
        assert pool._pool is not None
        now = set(pool._pool._processes)
        assert 1 <= len(started) <= len(now) <= 2 and os.getpid() not in now
        assert first <= started
        assert pool._pool is kept_pool and started <= now  # a new pool: new processes
        assert again <= now
    assert pool._pool is None
