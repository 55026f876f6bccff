"""Host-side tools for fluxdrive (SIL runner front-end, logs, plots, benchmarks).

This package never imports C code: it runs the SIL binary, reads its logs and
talks CAN.
"""

__version__ = "0.1.0"
