"""The ``touchbench`` command's exit statuses, in one place (listed in ``touchbench --help``)."""

from __future__ import annotations

OK = 0  #: everything asked was done
TASKS_FAILED = 1  #: the command ran, but at least one task (of a run, a reproduction) failed
USAGE = 2  #: the command line is wrong (an unknown option, a bad value): click's own status
DATA = 3  #: the input is wrong: a protocol, a data file, a model file, a results folder (one message)
INTERRUPTED = 130  #: stopped by Ctrl-C or SIGTERM; finished work is kept

HELP = ("Exit status: 0 done; 1 some task failed; 2 usage error; 3 data, protocol or file error "
        "(one message naming the file, line or field); 130 interrupted (Ctrl-C or SIGTERM; "
        "finished tasks are kept).")
