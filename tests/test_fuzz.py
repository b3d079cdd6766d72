"""A bounded fuzz run of the readers and the command line (issue 16); the long run is benchmarks/fuzz.py.

Derandomised, so the suite is deterministic; about 20 s in all. The
properties are those of tests/fuzzing.py: only the project's own errors,
exit codes 0, 2 or 3 and no traceback, no output or temporary file left by
a failed command, and a time bound per input (the deadline).
"""

import pytest

pytest.importorskip("hypothesis")

from hypothesis import HealthCheck, given, settings  # noqa: E402

from . import fuzzing  # noqa: E402

BOUNDED = settings(max_examples=1000, deadline=5000, derandomize=True, database=None,
                   suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


@BOUNDED
@given(fuzzing.mutated(fuzzing.MESH_SEEDS))
def test_mesh_reader_raises_only_its_own_errors(case):
    fuzzing.check_mesh_reader(*case)


@BOUNDED
@given(fuzzing.mutated(["map.txt", "map.npy"]))
def test_map_reader_raises_only_its_own_errors(case):
    fuzzing.check_map_reader(*case)


@settings(BOUNDED, max_examples=300)
@given(fuzzing.mutated(fuzzing.MESH_SEEDS + ["map.txt", "map.npy"]))
def test_transfer_exits_cleanly_and_leaves_nothing_on_failure(case):
    fuzzing.check_cli(*case, command="transfer")


@settings(BOUNDED, max_examples=200)
@given(fuzzing.mutated(["map.txt", "map.npy", "pairs.txt", "a.vts", "mesh.off", "mesh.ply"]))
def test_evaluate_exits_cleanly_on_bad_maps_and_ground_truth(case):
    fuzzing.check_cli(*case, command="evaluate")
