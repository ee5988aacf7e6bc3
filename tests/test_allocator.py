"""The allocator setting's environment (the speed it buys is a benchmark's: docs/performance.md)."""

from corobot_drake import allocator


def test_the_setting_joins_the_users_tunables_and_keeps_their_own_count():
    setting = f"{allocator.TUNABLE}={allocator.TCACHE_COUNT}"
    assert allocator.tuned_tunables(None) == setting
    assert allocator.tuned_tunables("glibc.malloc.arena_max=2") == \
        f"glibc.malloc.arena_max=2:{setting}"
    # A count the user chose stays theirs.
    assert allocator.tuned_tunables(f"{allocator.TUNABLE}=50") == f"{allocator.TUNABLE}=50"
    environment = allocator.tuned_environment({})
    assert allocator.is_tuned(environment) and not allocator.is_tuned({})
    assert not allocator.is_tuned({allocator.VARIABLE: "glibc.malloc.tcache_max=64"})
