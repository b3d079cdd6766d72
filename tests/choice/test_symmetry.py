"""Resolving the left/right mirror: orientation scores and the choice among near-tied configurations.

The test shape is bilaterally symmetric (an exact reflection z -> -z of its
vertices and faces) but front/back asymmetric, so the spectral cost cannot
tell the true map from its mirror image (ALGORITHM.md, "Pitfalls") and only
orientation can.
"""

import warnings

import numpy as np
import pytest
from scipy.spatial import cKDTree

import meshcorr
from meshcorr import datasets as ds
from meshcorr.errors import MeshWarning, ParameterError
from meshcorr.core.mesh import Mesh
from meshcorr.core.orientation import orient_outward, vertex_normals
from meshcorr.core.map_orientation import orientation_score
from meshcorr.stages.reorder import Configuration
from meshcorr.choice.symmetry import ConfigurationCandidate as Candidate, candidate_ranks, choose, metric_distortion, right_map_missing


def creature(subdivisions: int = 3):
    """A four-legged blob symmetric under z -> -z; returns vertices, faces, the reflection permutation."""
    V, F = ds.sphere(subdivisions=subdivisions)
    bumps = [((1.0, 0.35, 0.0), 0.6, 0.35), ((0.45, -0.85, 0.4), 0.7, 0.3), ((0.45, -0.85, -0.4), 0.7, 0.3),
             ((-0.5, -0.85, 0.4), 0.5, 0.3), ((-0.5, -0.85, -0.4), 0.5, 0.3), ((-1.0, 0.2, 0.0), 0.4, 0.3),
             ((0.0, 1.0, 0.0), 0.25, 0.5)]
    r = np.ones(len(V))
    for centre, amplitude, width in bumps:
        c = np.asarray(centre) / np.linalg.norm(centre)
        r += amplitude * np.exp(-np.sum((V - c) ** 2, axis=1) / (2 * width ** 2))
    reflection = cKDTree(V).query(V * [1, 1, -1])[1]
    return V * r[:, None] * [1.8, 1.0, 0.8], F, reflection


def bend(P, angle=0.5):
    """Bend the front half in the plane of symmetry (keeps the reflection an isometry)."""
    t = np.clip((P[:, 0] + 0.5) / 2.0, 0, 1)
    theta = angle * t * t * (3 - 2 * t)
    Q = P.copy()
    Q[:, 0] = np.cos(theta) * P[:, 0] - np.sin(theta) * P[:, 1]
    Q[:, 1] = np.sin(theta) * P[:, 0] + np.cos(theta) * P[:, 1]
    return Q


@pytest.fixture(scope="module")
def creature_and_bent_copy_with_mirror():
    """Source, a bent, rotated, scaled, re-indexed copy, the true map and its mirror image."""
    P, F, reflection = creature()
    rng = np.random.default_rng(1)
    R, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    R *= np.sign(np.linalg.det(R))
    perm = rng.permutation(len(P))
    inv = np.argsort(perm)
    Q = (bend(P) @ R.T * 1.7 + 3.0)[perm]
    return Mesh(P, F), Mesh(Q, inv[F]), inv, inv[reflection]


@pytest.fixture(scope="module")
def mirrored_target(creature_and_bent_copy_with_mirror):
    """The target reflected in space (faces reversed to stay outward): now the *other* map is right."""
    _, tgt, truth, mirror = creature_and_bent_copy_with_mirror
    return Mesh(tgt.vertices * [1, 1, -1], tgt.faces[:, ::-1]), mirror, truth


def mean_distance(mesh, mapping, truth):
    return float(np.linalg.norm(mesh.vertices[mapping] - mesh.vertices[truth], axis=1).mean())


# -- orientation ------------------------------------------------------------------------------


def test_orientation_score_of_true_map_is_high_and_of_mirror_low(creature_and_bent_copy_with_mirror):
    src, tgt, truth, mirror = creature_and_bent_copy_with_mirror
    assert orientation_score(src, tgt, truth) > 0.95
    assert orientation_score(src, tgt, mirror) < 0.05


def test_orientation_score_is_robust_to_vertex_noise(creature_and_bent_copy_with_mirror):
    src, tgt, truth, mirror = creature_and_bent_copy_with_mirror
    rng = np.random.default_rng(0)
    noisy = truth.copy()
    hit = rng.random(len(noisy)) < 0.2  # a fifth of the vertices mapped to a random neighbour
    tree = cKDTree(tgt.vertices)
    noisy[hit] = tree.query(tgt.vertices[truth[hit]], k=4)[1][:, 3]
    noisy_mirror = noisy.copy()
    noisy_mirror[:] = tree.query(tgt.vertices[mirror], k=1)[1]
    noisy_mirror[hit] = tree.query(tgt.vertices[mirror[hit]], k=4)[1][:, 3]
    assert orientation_score(src, tgt, noisy) > 0.8
    assert orientation_score(src, tgt, noisy_mirror) < 0.2


def test_orientation_ignores_face_winding_of_the_input(creature_and_bent_copy_with_mirror):
    src, tgt, truth, _ = creature_and_bent_copy_with_mirror
    rng = np.random.default_rng(3)
    faces = tgt.faces.copy()
    flip = rng.random(len(faces)) < 0.3
    faces[flip] = faces[flip, ::-1]
    inward = Mesh(tgt.vertices, tgt.faces[:, ::-1])
    scrambled = Mesh(tgt.vertices, faces)
    assert orientation_score(src, scrambled, truth) == pytest.approx(orientation_score(src, tgt, truth))
    assert orientation_score(src, inward, truth) == pytest.approx(orientation_score(src, tgt, truth))


def test_winding_repair_and_outward_normals():
    V, F = ds.sphere(subdivisions=2)
    rng = np.random.default_rng(0)
    scrambled = F.copy()
    flip = rng.random(len(F)) < 0.4
    scrambled[flip] = scrambled[flip, ::-1]
    o = orient_outward(V, scrambled)
    assert o.reliable and o.reason == "" and o.n_flipped == int(flip.sum())
    np.testing.assert_array_equal(np.sort(o.faces, axis=1), np.sort(F, axis=1))
    normals, areas = vertex_normals(V, o.faces)
    np.testing.assert_allclose(np.einsum("ij,ij->i", normals, V), 1.0, atol=0.02)  # outward on a sphere
    assert areas.sum() == pytest.approx(4 * np.pi, rel=0.02)


def test_open_disc_orientation_is_unreliable():
    V, F = ds.sphere(subdivisions=2)
    keep = V[:, 2] > 0.6  # a shallow cap: almost flat, its inside is undefined
    index = np.cumsum(keep) - 1
    cap = index[F[keep[F].all(axis=1)]]
    o = orient_outward(V[keep] * [1, 1, 0.0] + [0, 0, 1], cap)
    assert not o.reliable and "open" in o.reason


def test_non_orientable_strip_is_reported():
    # A Moebius strip: two rails joined crosswise after a half twist.
    n = 16
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    rails = [np.column_stack([(1 + s * np.cos(t / 2)) * np.cos(t), (1 + s * np.cos(t / 2)) * np.sin(t),
                              s * np.sin(t / 2)]) for s in (0.3, -0.3)]
    V = np.vstack(rails)  # top rail 0..n-1, bottom rail n..2n-1
    F = []
    for i in range(n):
        a, d = i, n + i
        b, c = (i + 1, n + i + 1) if i < n - 1 else (n, 0)  # the twist swaps the rails
        F += [[a, b, c], [a, c, d]]
    o = orient_outward(V, np.array(F))
    assert not o.reliable and "orientable" in o.reason


def test_orientation_score_bad_maps(creature_and_bent_copy_with_mirror):
    src, tgt, truth, _ = creature_and_bent_copy_with_mirror
    with pytest.raises(ParameterError, match="one entry per source vertex"):
        orientation_score(src, tgt, truth[:-1])
    bad = truth.copy()
    bad[0] = tgt.n_vertices
    with pytest.raises(ParameterError, match="target vertex indices"):
        orientation_score(src, tgt, bad)
    with pytest.raises(ParameterError, match="n_neighbors"):
        orientation_score(src, tgt, truth, n_neighbors=1)


# -- choosing among candidates ------------------------------------------------------------------


def _candidate(rank, orientation, curvature, distortion=np.nan):
    return Candidate(rank, Configuration((0, 1), (1, 1 if rank % 2 == 0 else -1), 0.1 + rank),
                     orientation, curvature, distortion, np.zeros(1, dtype=np.int64))


@pytest.mark.parametrize("order", [(0, 1), (1, 0)])
def test_auto_prefers_orientation_whatever_comes_first(order):
    preserving, mirror = _candidate(0, 0.9, 0.30), _candidate(1, 0.1, 0.29)
    candidates = [(preserving, mirror)[i] for i in order]
    chosen, other = choose(candidates, "auto")
    assert chosen is preserving and other is mirror
    chosen, other = choose(candidates, "mirror")
    assert chosen is mirror and other is preserving
    chosen, other = choose(candidates, "cost")
    assert chosen is candidates[0] and other is candidates[1]


def test_auto_rejects_a_half_turn_by_its_curvature():
    half_turn = _candidate(0, 0.9, 0.45, 0.019)  # preserves orientation, nose to the back of the head
    right, mirror = _candidate(2, 0.85, 0.30, 0.021), _candidate(1, 0.1, 0.31, 0.020)
    front_back = _candidate(3, 0.1, 0.44, 0.019)  # the half turn's mirror image
    chosen, other = choose([half_turn, mirror, right, front_back], "auto")
    assert chosen is right and other is mirror


def test_unreliable_orientation_falls_back_to_distortion():
    a, b = _candidate(0, 0.1, 0.5, 0.01), _candidate(1, 0.9, 0.3, 0.02)
    chosen, other = choose([a, b], "auto", orientation_reliable=False)
    assert chosen is a and other is b
    chosen, other = choose([a, b], "auto")
    assert chosen is b and other is a


def test_the_alternative_has_the_other_orientation():
    # A second orientation-preserving candidate agrees better than the mirror, yet the
    # alternative kept is the mirror: the best candidate of the opposite orientation.
    right, second, mirror = _candidate(0, 0.9, 0.30), _candidate(1, 0.8, 0.31), _candidate(2, 0.1, 0.35)
    chosen, other = choose([right, second, mirror], "auto")
    assert chosen is right and other is mirror
    chosen, other = choose([right, second, mirror], "mirror")
    assert chosen is mirror and other is right
    # Without a reliable orientation the alternative is the next least distorted, any orientation.
    a, b, c = _candidate(0, 0.1, 0.5, 0.01), _candidate(1, 0.1, 0.5, 0.02), _candidate(2, 0.9, 0.3, 0.03)
    chosen, other = choose([a, b, c], "auto", orientation_reliable=False)
    assert chosen is a and other is b


def test_an_orientation_score_of_one_half_counts_as_preserving():
    edge, mirror = _candidate(0, 0.5, 0.30), _candidate(1, 0.1, 0.29)
    chosen, other = choose([edge, mirror], "auto")
    assert chosen is edge and other is mirror
    # ... also for the alternative of a reversing choice: the 0.5 one, not the better reversing one.
    cheapest, edge, reversing = _candidate(0, 0.1, 0.5), _candidate(1, 0.5, 0.4), _candidate(2, 0.1, 0.3)
    chosen, other = choose([cheapest, edge, reversing], "cost")
    assert chosen is cheapest and other is edge


def test_right_map_missing_when_preserving_candidates_agree_worse():
    mirror, half_turn = _candidate(0, 0.1, 0.36), _candidate(1, 0.9, 0.44)
    assert right_map_missing([mirror, half_turn])  # 0.44 > 1.15 x 0.36
    assert not right_map_missing([mirror, half_turn, _candidate(4, 0.9, 0.34)])
    assert not right_map_missing([mirror, _candidate(1, 0.9, 0.40)])  # within 15 %
    assert not right_map_missing([_candidate(0, 0.1, 0.25), _candidate(1, 0.9, 0.5)], ratio=2.0)  # at it
    assert right_map_missing([mirror])  # nothing preserves orientation
    assert not right_map_missing([half_turn])  # nothing to compare with
    with pytest.raises(ParameterError, match="'ratio' parameter"):
        right_map_missing([mirror], ratio=0.5)


def test_choose_errors():
    with pytest.raises(ParameterError, match="'symmetry' parameter must be one of"):
        choose([_candidate(0, 1.0, 0.0)], "left")
    with pytest.raises(ValueError, match="No candidate"):
        choose([], "auto")
    assert choose([_candidate(0, 1.0, 0.0)], "mirror")[1] is None


def test_candidate_ranks_keep_near_ties_and_the_runner_up():
    configs = [Configuration((0,), (1,), c) for c in (1.0, 1.1, 1.5, 1.2, 3.0)]
    assert candidate_ranks(configs, tolerance=0.25) == [0, 1, 3]
    assert candidate_ranks(configs, tolerance=0.0) == [0, 1]
    assert candidate_ranks(configs, tolerance=1.0, max_candidates=3) == [0, 1, 3]
    assert candidate_ranks(configs, tolerance=1.0, max_candidates=2) == [0, 1]  # the smallest allowed
    assert candidate_ranks(configs[:1]) == [0]
    with pytest.raises(ParameterError, match="symmetry_tolerance"):
        candidate_ranks(configs, tolerance=-1)
    with pytest.raises(ParameterError, match="max_candidates"):
        candidate_ranks(configs, max_candidates=1)


def test_metric_distortion_is_zero_for_an_isometry_and_shares_rows():
    D = np.array([[0.0, 1.0, 2.0], [1.0, 0.0, 1.0], [2.0, 1.0, 0.0]])
    rows: dict = {}
    assert metric_distortion(D.__getitem__, D.__getitem__, np.arange(3), np.array([0, 2]), rows) == 0.0
    assert set(rows) == {0, 2}
    swapped = metric_distortion(D.__getitem__, D.__getitem__, np.array([1, 0, 2]), np.array([0]))
    assert swapped == pytest.approx(1.0 / 3.0)  # |[0, 1, 2] - [0, 1, 1]| averaged


# -- end to end -------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def results(creature_and_bent_copy_with_mirror, mirrored_target):
    src, tgt, _, _ = creature_and_bent_copy_with_mirror
    mtgt = mirrored_target[0]
    return {
        "auto": meshcorr.match(src, tgt),
        "cost": meshcorr.match(src, tgt, symmetry="cost", refine=False),
        "mirror": meshcorr.match(src, tgt, symmetry="mirror", refine=False),
        "auto-mirrored-target": meshcorr.match(src, mtgt),
        "cost-mirrored-target": meshcorr.match(src, mtgt, symmetry="cost", refine=False),
    }


def test_near_tied_costs_put_the_mirror_among_the_candidates(results):
    cands = results["auto"].candidates
    assert len(cands) >= 2
    assert cands[1]["cost"] == pytest.approx(cands[0]["cost"], rel=0.05)
    scores = sorted(c["orientation"] for c in cands[:2])
    assert scores[0] < 0.2 and scores[1] > 0.8


@pytest.mark.parametrize("key, which", [("auto", 2), ("auto-mirrored-target", 1)])
def test_auto_maps_to_the_right_side_from_both_sign_sets(results, creature_and_bent_copy_with_mirror, mirrored_target,
                                                          key, which):
    src, tgt, truth, mirror = creature_and_bent_copy_with_mirror
    target, right, wrong = (tgt, truth, mirror) if which == 2 else mirrored_target
    result = results[key]
    scale = np.sqrt(target.area)
    assert mean_distance(target, result.map, right) / scale < 0.05
    assert mean_distance(target, result.map, wrong) / scale > 0.1
    assert mean_distance(target, result.alternative_map, wrong) / scale < 0.08  # the mirror is kept
    chosen = [c for c in result.candidates if c["chosen"]]
    assert len(chosen) == 1 and chosen[0]["orientation"] > 0.8
    assert result.orientation_reliable is True


def test_cost_cannot_tell_the_two_sides_apart(results):
    # The shape is exactly symmetric: the true map and its mirror cost the same, so
    # "cost" takes whichever of the tie comes first; on the mirrored target the right
    # answer is the other one.
    for key in ("cost", "cost-mirrored-target"):
        result = results[key]
        assert result.configuration.cost == min(c["cost"] for c in result.candidates)
        assert result.runner_up.cost == pytest.approx(result.configuration.cost, rel=1e-6)


def test_mirror_option_gives_the_other_side(results, creature_and_bent_copy_with_mirror):
    _, tgt, truth, mirror = creature_and_bent_copy_with_mirror
    result = results["mirror"]
    assert mean_distance(tgt, result.map, mirror) / np.sqrt(tgt.area) < 0.05
    summary = result.summary()
    assert summary["params"]["symmetry"] == "mirror"
    assert [c["chosen"] for c in summary["candidates"]].count(True) == 1
    chosen = next(c for c in summary["candidates"] if c["chosen"])
    kept = next(c for c in summary["candidates"] if c["alternative"])
    # The mirror reverses orientation, the kept alternative (the right map) preserves it; the
    # mirror leaves mean curvature as it is, so both agree with the target's about equally
    # (measured 0.2915 and 0.2891), better than the front/back flips (0.3552).
    assert chosen["orientation"] < 0.2 and kept["orientation"] > 0.8
    assert chosen["curvature"] == pytest.approx(kept["curvature"], rel=0.05)
    others = [c["curvature"] for c in summary["candidates"] if not (c["chosen"] or c["alternative"])]
    assert all(max(chosen["curvature"], kept["curvature"]) < other for other in others)
    assert all(c["distortion"] is None for c in summary["candidates"])


@pytest.mark.parametrize("only", [0, 1])
def test_candidates_are_widened_when_the_right_map_is_missing(creature_and_bent_copy_with_mirror, monkeypatch, only):
    # Score a single near-tied configuration: rank 0 or 1, one of which is the mirror
    # image. With the mirror alone no candidate preserves orientation, so the pipeline
    # must widen the set and still find the right side.
    import meshcorr.choice.symmetry as pipeline

    src, tgt, truth, mirror = creature_and_bent_copy_with_mirror
    monkeypatch.setattr(pipeline, "candidate_ranks", lambda configurations: [only])
    result = meshcorr.match(src, tgt, refine=False)
    scale = np.sqrt(tgt.area)
    assert mean_distance(tgt, result.map, truth) / scale < 0.05
    widened = len(result.candidates) == 6
    assert widened == (result.candidates[0]["orientation"] < 0.5)


def test_open_mesh_warns_that_orientation_is_unreliable():
    V, F = ds.sphere(subdivisions=2)
    keep = V[:, 2] > 0.6
    index = np.cumsum(keep) - 1
    flat = (V[keep] * [1, 1, 0.0], index[F[keep[F].all(axis=1)]])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = meshcorr.match(flat, flat, refine=False, reorder="signs")
    assert result.orientation_reliable is False
    assert any(issubclass(w.category, MeshWarning) and "orientation" in str(w.message) for w in caught)
    assert all(c["distortion"] is not None for c in result.candidates)  # distortion decides here


@pytest.mark.parametrize("kwargs, message", [
    ({"symmetry": "left"}, "'symmetry' parameter must be one of"),
    ({"anchor_scale": "meters"}, "'anchor_scale' parameter must be one of"),
    ({"refine": "yes"}, "'refine' parameter must be True or False"),
    ({"refine_k": 1}, "'refine_k' parameter must be an int >= 2"),
])
def test_bad_symmetry_options_are_rejected(creature_and_bent_copy_with_mirror, kwargs, message):
    src = creature_and_bent_copy_with_mirror[0]
    with pytest.raises(ParameterError, match=message):
        meshcorr.match(src, src, **kwargs)


# -- command line -------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def creature_files_with_mirror(creature_and_bent_copy_with_mirror, tmp_path_factory):
    import trimesh

    src, tgt, truth, mirror = creature_and_bent_copy_with_mirror
    folder = tmp_path_factory.mktemp("sym")
    paths = folder / "source.off", folder / "target.off"
    for mesh, path in zip((src, tgt), paths):
        trimesh.Trimesh(mesh.vertices, mesh.faces, process=False).export(path)
    return str(paths[0]), str(paths[1]), truth, mirror


def test_cli_writes_the_alternative_and_reports_candidates(creature_files_with_mirror, tmp_path, capsys):
    import json

    from meshcorr.cli import main

    src, tgt, truth, mirror = creature_files_with_mirror
    out, alt = tmp_path / "map.txt", tmp_path / "mirror.npy"
    code = main(["match", src, tgt, "-o", str(out), "--alternative-out", str(alt), "--json",
                 "--symmetry", "auto", "--no-refine", "--anchor-scale", "geodesic"])
    assert code == 0
    mapping, alternative = np.loadtxt(out, dtype=np.int64), np.load(alt)
    assert np.mean(mapping == truth) > 0.2 and np.mean(mapping == mirror) < 0.05
    assert np.mean(alternative == mirror) > 0.2
    summary = json.loads(capsys.readouterr().out)
    assert summary["params"]["refine"] is False and summary["params"]["anchor_scale"] == "geodesic"
    assert summary["orientation_reliable"] is True
    scores = {c["chosen"]: c["orientation"] for c in summary["candidates"] if c["chosen"] or c["alternative"]}
    assert scores[True] > 0.8 and scores[False] < 0.2


@pytest.mark.parametrize("extra, message", [
    (["--symmetry", "left"], "invalid choice"),
    (["--alternative-out", "/no/such/folder/alt.txt"], "does not exist"),
])
def test_cli_symmetry_errors(creature_files_with_mirror, tmp_path, capsys, extra, message):
    from meshcorr.cli import main

    src, tgt, _, _ = creature_files_with_mirror
    with pytest.raises(SystemExit) if "invalid" in message else warnings.catch_warnings():
        code = main(["match", src, tgt, "-o", str(tmp_path / "m.txt"), "-q"] + extra)
        assert code == 2
    assert message in capsys.readouterr().err
