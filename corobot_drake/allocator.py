"""The C allocator's setting that makes a simulation step cheaper: glibc's per-thread cache.

Every 10 ms step, Drake's contact solver builds its problem afresh: thousands of small blocks
allocated and freed (callgrind: ~3,000 `operator new` a step for the default scene). glibc
keeps at most 7 freed blocks of each size in a thread's cache (`tcache`); the others go
through its bins, sorted and merged, at several times the cost. A cache of `TCACHE_COUNT`
blocks per size serves a step's allocations from the blocks the last step freed. It changes
no result, only the time (`python tools/bench.py --allocator`; docs/performance.md).

glibc reads the setting once, when a process starts (the `GLIBC_TUNABLES` environment
variable), so it applies to the processes this package starts (a study's Ray workers, through
`tuned_environment`) and to a process started with it:

    export GLIBC_TUNABLES=glibc.malloc.tcache_count=1000
"""

import os

TCACHE_COUNT = 1000
"""Freed blocks of each size a thread keeps (glibc's default: 7). 100 already gets most of
the gain, 500 to 65535 the same (callgrind, one simulated second of the benchmark)."""
TUNABLE = "glibc.malloc.tcache_count"
VARIABLE = "GLIBC_TUNABLES"


def tuned_tunables(current: str | None) -> str:
    """`GLIBC_TUNABLES` with the cache setting added (a value the user gave for it stays)."""
    settings = [s for s in (current or "").split(":") if s]
    if any(s.split("=", 1)[0] == TUNABLE for s in settings):
        return ":".join(settings)
    return ":".join([*settings, f"{TUNABLE}={TCACHE_COUNT}"])


def tuned_environment(environ=None) -> dict[str, str]:
    """The variables to give a process this package starts ({`VARIABLE`: value})."""
    environ = os.environ if environ is None else environ
    return {VARIABLE: tuned_tunables(environ.get(VARIABLE))}


def is_tuned(environ=None) -> bool:
    """Whether a process with this environment starts with the cache setting."""
    environ = os.environ if environ is None else environ
    return any(s.split("=", 1)[0] == TUNABLE for s in environ.get(VARIABLE, "").split(":"))
