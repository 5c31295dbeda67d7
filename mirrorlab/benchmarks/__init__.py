"""The timing benchmarks that ship with the package: ``mirrorlab bench speed``
(:mod:`mirrorlab.benchmarks.speed`, against pyrender and at scale, on the scenes of
:mod:`mirrorlab.benchmarks.scale`). ``mirrorlab bench accuracy`` is
:mod:`mirrorlab.accuracy`. The clone's ``bench/`` holds the scripts that need a clone
(a hand-written PyOpenGL frame, perf profiles, soak runs)."""
