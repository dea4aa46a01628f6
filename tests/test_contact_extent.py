"""The contact extent and reference width of a history: one normal solve per distinct load.

``simulator.contact_edges`` solves the normal problem once per distinct (P, M)
sample with P > 0 (warm-started along the history); the field stations (largest extent) and the general
solver's reference width (widest contact) are both read from it, and a run
computes it once.
"""
from __future__ import annotations

import numpy as np
import pytest
from helpers import example_text

import halfslip as hs
from halfslip import simulator
from halfslip.geometry import NormalProblem


def counted(problem: NormalProblem) -> list:
    """Record the (P, M) of every ``problem.solve`` call in the returned list."""
    calls = []
    solve = problem.solve

    def wrapper(P, M=0.0, near=None):
        calls.append((float(P), float(M)))
        return solve(P, M, near=near)

    problem.solve = wrapper
    return calls


@pytest.fixture(scope="module")
def dovetail():
    """The dovetail example (a moment: no closed form) with 4 cycles instead of 20."""
    return hs.parse_scene(example_text("dovetail", **{"count: 20": "count: 4"}))


def test_one_solve_per_distinct_load_and_the_same_extent_and_width_as_every_sample(dovetail):
    h = dovetail.history
    assert np.any(h.M != 0.0) and not np.all(h.P > 0.0)  # a moment, and a sample without contact (t = 0)
    problem = NormalProblem(dovetail.profile, dovetail.material.compliance)
    calls = counted(problem)

    edges = simulator.contact_edges(dovetail, problem)

    distinct = {(float(P), float(M)) for P, M in zip(h.P, h.M) if P > 0}
    assert len(calls) == len(distinct) and set(calls) == distinct  # each distinct load once, none twice
    assert len(distinct) < h.P.size / 3  # the cycles repeat their samples: far fewer solves than samples
    # the stations and the width from these edges: no further solve
    points = dovetail.output.points
    x = simulator.field_stations(dovetail, problem, points, edges)
    width = simulator.reference_width(dovetail, problem, edges)
    assert len(calls) == len(distinct)

    # brute force: every sample of the history, solved afresh
    left, right, widest = np.inf, -np.inf, -np.inf
    fresh = NormalProblem(dovetail.profile, dovetail.material.compliance)
    for P, M in zip(h.P, h.M):
        if P > 0:
            sol = fresh.solve(float(P), float(M))
            left, right, widest = min(left, sol.left), max(right, sol.right), max(widest, sol.right - sol.left)
    # the solves are warm-started along the history: they agree with cold ones to the normal solver's
    # tolerance (measured 2.5e-15 of the width here; 1e-12 as the warm-start tests)
    tol = 1e-12 * widest
    margin = 0.02 * (right - left)
    np.testing.assert_allclose(x, np.linspace(left - margin, right + margin, points), rtol=0, atol=tol)
    assert edges.extent == pytest.approx((left, right), abs=tol)
    assert width == pytest.approx(widest, abs=tol)
    # the order in which the samples first occur, each solve after the previous one
    _, first = np.unique(np.column_stack([h.P, h.M])[h.P > 0], axis=0, return_index=True)
    assert calls == [(float(P), float(M)) for P, M in np.column_stack([h.P, h.M])[h.P > 0][np.sort(first)]]
    # the public forms without edges solve for themselves and agree
    np.testing.assert_array_equal(simulator.field_stations(dovetail, problem, points), x)
    assert simulator.reference_width(dovetail, problem) == width


def test_a_run_solves_the_edges_once_for_the_stations_and_the_width(dovetail, monkeypatch):
    assert dovetail.output.fields and simulator.choose_method(dovetail) == "general"
    runs = []
    edges_of = simulator.contact_edges

    def once(scene, problem):
        runs.append(scene)
        return edges_of(scene, problem)

    monkeypatch.setattr(simulator, "contact_edges", once)
    run = simulator._Run(dovetail, "general")
    assert len(runs) == 1
    problem = NormalProblem(dovetail.profile, dovetail.material.compliance)
    np.testing.assert_array_equal(run.save.x, simulator.field_stations(dovetail, problem, dovetail.output.points))


def test_symmetric_profile_without_moment_needs_no_solve(monkeypatch):
    scene = hs.parse_scene(example_text("hertz_pad"))
    h = scene.history
    assert scene.profile.symmetric and not np.any(h.M) and np.unique(h.P[h.P > 0]).size > 10
    problem = NormalProblem(scene.profile, scene.material.compliance)
    calls = counted(problem)
    runs = []
    monkeypatch.setattr(simulator, "contact_edges", lambda *a: runs.append(a))

    width = simulator.reference_width(scene, problem)
    x = simulator.field_stations(scene, problem, scene.output.points)
    simulator._Run(scene, "general")  # the general solver's width too

    assert calls == [] and runs == []
    a = float(problem.half_width(float(np.max(h.P))))
    assert width == 2.0 * a
    np.testing.assert_array_equal(x, np.linspace(-1.02 * a, 1.02 * a, scene.output.points))
    # the closed form is the widest contact of every sample
    fresh = NormalProblem(scene.profile, scene.material.compliance)
    widest = max(fresh.solve(float(P)).right - fresh.solve(float(P)).left for P in h.P if P > 0)
    assert width == pytest.approx(widest, rel=1e-15)


def test_the_general_solver_reuses_the_start_up_solutions(dovetail):
    """The steps that end on a history sample take the normal solution the start-up found for it instead
    of solving again (dovetail, 4 cycles: 132 distinct samples solved at start-up; over its first 159
    steps the marching then solves 9 sub-steps, against 168 solves without the start-up's), and the run
    is the same as with a solve at every step to the normal solver's tolerance (warm starts from other
    neighbours: measured 7e-15 of the dissipation, edges to rounding; asserted 1e-9, the golden runs'
    tolerance)."""
    from halfslip.state import Loads

    problem = NormalProblem(dovetail.profile, dovetail.material.compliance)
    edges = simulator.contact_edges(dovetail, problem)
    h = dovetail.history
    assert len(edges.solutions) == len(edges.P) == len(np.unique(np.column_stack([h.P, h.M])[h.P > 0], axis=0))
    reusing = simulator.build_method(dovetail, "general", problem, None, edges)
    alone = simulator.build_method(dovetail, "general", problem, None, None)
    assert reusing.width == alone.width  # the same start-up, solved again
    states = [reusing.initial_state(), alone.initial_state()]
    for i in range(1, 160):
        loads = Loads(h.P[i], h.Q[i], h.M[i], h.sigma[i])
        states = [s.step(st, float(h.t[i]), loads)[0] for s, st in zip((reusing, alone), states)]
    a, b = states
    assert reusing.counters["normal_solves"] < alone.counters["normal_solves"] / 2, (
        reusing.counters["normal_solves"], alone.counters["normal_solves"])
    assert a.dissipation == pytest.approx(b.dissipation, rel=1e-9)
    W = a.contact_right - a.contact_left
    for u, v in ((a.stick_left, b.stick_left), (a.stick_right, b.stick_right), (a.contact_left, b.contact_left)):
        assert abs(u - v) <= 1e-9 * W
