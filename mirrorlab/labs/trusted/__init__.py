"""The trusted side of the labs: what runs outside the sandbox.

:mod:`.sandbox` starts the student's file in bubblewrap with nothing of this package in
reach; :mod:`.pipe` reads what comes out of it, every size capped before it is read;
:mod:`.calls` and :mod:`.call_executor` validate each OpenGL, GLU and lab call, execute it in
this process's own context and note what it did; :mod:`.lab_run` drives one file through a
lab and collects the :class:`~.evidence.Evidence` the judges (:mod:`.lab20`,
:mod:`.spheremap`, :mod:`.cubemap`, :mod:`.frame`) read. :mod:`.checker`, :mod:`.grading`,
:mod:`.release` and :mod:`.report` are the commands around them.
"""
