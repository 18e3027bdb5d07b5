"""benchmark.world.bounded_lsq: the grasp planner's least squares without BLAS, against scipy's."""

import math

import numpy as np
import pytest
from scipy.optimize import least_squares

from benchmark.world import bounded_lsq

TIGHT = {"ftol": 1e-15, "xtol": 1e-15, "gtol": 1e-15}
T = np.linspace(0.0, 3.0, 20)
Y = np.array([2.5 * math.exp(-1.3 * t) + 0.2 + 0.01 * math.sin(7 * t) for t in T])


def rosenbrock(x):
    return np.array([10 * (x[1] - x[0] * x[0]), 1 - x[0]])


def decay(p):  # a residual of 20 points, not zero at the minimum; math.exp on scalars (no SIMD ufunc)
    return np.array([p[0] * math.exp(-p[1] * t) + p[2] - y for t, y in zip(T, Y)])


@pytest.mark.parametrize("fun, x0, lb, ub, x_scale", [
    (rosenbrock, [-1.2, 1.0], [-2, -2], [2, 2], [1, 1]),  # the interior minimum (1, 1)
    (rosenbrock, [-1.2, 1.0], [-2, -2], [0.5, 2], [1, 1]),  # x0 held at its upper bound
    (rosenbrock, [-1.2, 2.0], [-2, 1.5], [2, 3], [1, 1]),  # x1 held at its lower bound, x0 inside
    (decay, [1, 1, 0.5], [0, 0, 0], [10, 10, 1], [1, 1, 0.1]),
    (decay, [1, 1, 0.5], [0, 0, 0.25], [10, 10, 1], [1, 1, 0.1]),  # the offset held at 0.25
])
def test_the_solver_finds_scipys_minimum_of_a_small_bounded_problem(fun, x0, lb, ub, x_scale):
    lb, ub = np.array(lb, float), np.array(ub, float)
    ours = bounded_lsq.solve(fun, x0, lb, ub, np.array(x_scale, float), **TIGHT)
    theirs = least_squares(fun, x0, bounds=(lb, ub), x_scale=np.array(x_scale, float), **TIGHT)
    assert np.all((lb <= ours.x) & (ours.x <= ub))
    np.testing.assert_allclose(ours.x, theirs.x, rtol=0, atol=1e-8)  # measured: <= 8e-10
    assert ours.cost == pytest.approx(theirs.cost, rel=1e-12, abs=1e-20)
    assert ours.status in ("ftol", "xtol", "gtol")


def test_the_solver_stops_at_its_evaluation_budget_with_the_best_point_so_far():
    x0 = np.array([-1.2, 1.0])
    lb, ub = np.full(2, -2.0), np.full(2, 2.0)
    r = bounded_lsq.solve(rosenbrock, x0, lb, ub, np.ones(2), max_nfev=5)
    assert r.status == "max_nfev" and r.nfev == 5
    assert r.cost < bounded_lsq.half_sum_squares(rosenbrock(x0))
    assert r.cost == bounded_lsq.half_sum_squares(rosenbrock(r.x))


def test_forward_differences_step_back_from_an_upper_bound():
    f = lambda x: np.array([x[0] * x[0], 3 * x[1]])  # noqa: E731
    x = np.array([1.0, 0.5])
    J = bounded_lsq.jacobian(f, x, f(x), np.zeros(2), np.array([1.0, 2.0]))
    assert J[0, 0] < 2.0 < J[0, 0] + 1e-7  # a backward difference at the bound x0 = 1: 2 - h
    assert J[1, 1] == pytest.approx(3.0, rel=1e-7) and J[0, 1] == 0 and J[1, 0] == 0
