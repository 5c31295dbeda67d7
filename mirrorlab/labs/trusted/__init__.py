"""The trusted side of the labs: what runs outside the sandbox, shared by every lab.

:mod:`.sandbox` starts the student's file in bubblewrap with nothing of this package in
reach; :mod:`.pipe` reads what comes out of it, every size capped before it is read;
:mod:`.calls` and :mod:`.call_executor` validate each OpenGL, GLU and lab call, execute it
in this process's own context and note what it did; :mod:`.lab_run` drives one file
through a lab, in the checker's GL process (:mod:`.gl_process`), and collects the
:class:`~.evidence.Evidence` each lab's judge (its package's ``judge.py``, with
:mod:`.judging`) reads. :mod:`.checker`, :mod:`.grading`, :mod:`.release` and
:mod:`.report` are the commands around them, :mod:`.window` is ``lab run``'s window. Each
of them asks the lab registry (:mod:`mirrorlab.labs`) for a lab's own pieces.
"""
