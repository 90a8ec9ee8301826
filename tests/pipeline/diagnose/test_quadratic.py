"""The second-order response model of pipeline.diagnose.quadratic against hand-made functions
with known coefficients and minima (its match to exact reanalysis of a bowed member is in
test_screen.py, where the frame fixture is)."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from structures.common.errors import InputError
from pipeline.diagnose.quadratic import (RAY, coefficients, line_search, line_searches,
                                         monomials, n_columns, quadratic_fit, sample_points,
                                         trust_box)

# r(x) = R0 + A x + C11 x1^2 + C22 x2^2 + C12 x1 x2, three data rows
R0 = np.array([1.0, -2.0, 0.5])
A = np.array([[3.0, -1.0], [0.5, 2.0], [-4.0, 0.0]])
C = np.array([[10.0, -3.0, 7.0], [0.0, 20.0, -5.0], [40.0, 1.0, 0.0]])   # columns c11, c22, c12


def _quadratic(x):
    x = np.asarray(x, float)
    return R0 + A @ x + C @ np.array([x[0] ** 2, x[1] ** 2, x[0] * x[1]])


@pytest.mark.parametrize("scheme", ["one_sided", "centred"])
@pytest.mark.parametrize("reference", [(0.05, 0.05), (0.05, -0.05), (0.2, 0.01)])
def test_coefficients_of_a_quadratic_are_exact(reference, scheme):
    points = sample_points(reference, scheme)
    assert points.shape == (5, 2) and n_columns(2) == 5
    s = coefficients(R0, [_quadratic(p) for p in points], reference, scheme)
    assert s == pytest.approx(np.column_stack([A, C]), rel=1e-9, abs=1e-9)
    x = np.array([0.07, -0.02])
    assert R0 + s @ monomials(x) == pytest.approx(_quadratic(x), rel=1e-12, abs=1e-12)


def test_one_parameter_model_by_hand():
    # r(x) = 1 - 40 x + 400 x^2 = (1 - 20 x)^2: samples at h = 0.05, 0.1 give r = 0, 1
    s = coefficients([1.0], [[0.0], [1.0]], [0.05])
    assert s == pytest.approx(np.array([[-40.0, 400.0]]), rel=1e-12)
    x, chi2 = quadratic_fit([1.0], s, [0.05], [0.0], [0.15])
    assert x == pytest.approx([0.05], abs=1e-7) and chi2 == pytest.approx(0.0, abs=1e-12)


def test_quadratic_fit_finds_the_zero_inside_the_sampled_span():
    # r = (x1^2 - 0.06^2, x2 - 0.03, x1 x2 - 0.0018): zero at (0.06, 0.03) only (x1 >= 0)
    r0 = np.array([-0.0036, -0.03, -0.0018])
    s = np.array([[0, 0, 1.0, 0, 0], [0, 1.0, 0, 0, 0], [0, 0, 0, 0, 1.0]])
    x, chi2 = quadratic_fit(r0, s, (0.05, 0.05), (0.0, 0.0), (0.15, 0.15))
    assert x == pytest.approx([0.06, 0.03], abs=1e-6) and chi2 < 1e-14


def test_quadratic_fit_stays_in_the_sampled_span_and_bounds():
    # r = (x1 - 0.13, x2 + 0.02): the zero lies beyond 2 h_1 = 0.1 and below bound x2 >= 0
    r0, s = np.array([-0.13, 0.02]), np.array([[1.0, 0, 0, 0, 0], [0, 1.0, 0, 0, 0]])
    assert [b.tolist() for b in trust_box((0.05, 0.05), (0, 0), (0.15, 0.15))] == \
        [[0.0, 0.0], [0.1, 0.1]]
    x, chi2 = quadratic_fit(r0, s, (0.05, 0.05), (0.0, 0.0), (0.15, 0.15))
    assert x == pytest.approx([0.1, 0.0], abs=1e-9)
    assert chi2 == pytest.approx(0.03 ** 2 + 0.02 ** 2, rel=1e-6)
    # no lower point in the span: x = 0 and the starting chi^2
    x, chi2 = quadratic_fit(np.array([1.0]), np.array([[1.0, 1.0]]), [0.05], [0.0], [0.15])
    assert x == pytest.approx([0.0]) and chi2 == pytest.approx(1.0)


def test_line_search_reaches_beyond_the_fit_to_the_bounds():
    # r = |x| - 0.13 along the ray through (0.06, 0.08) (|x| = 0.1): the bound x2 <= 0.15 ends
    # the ray at t = 1.875; the best sampled size is within half a ray step of 0.13
    seen = []

    def residual_at(x):
        seen.append(np.array(x))
        return np.array([np.linalg.norm(x) - 0.13])

    found = line_search(residual_at, [0.06, 0.08], [0.0, 0.0], [0.15, 0.15])
    x, r, chi2 = found
    step = 0.1 * 1.875 / (2 * len(RAY))
    assert abs(np.linalg.norm(x) - 0.13) <= step
    assert x[1] / x[0] == pytest.approx(0.08 / 0.06, rel=1e-12)            # on the ray
    assert chi2 == pytest.approx(r[0] ** 2, rel=1e-12)
    assert max(p[1] for p in seen) == pytest.approx(0.15, rel=1e-12)       # reached the bound
    assert all(np.all(p >= 0) and np.all(p <= 0.15 + 1e-15) for p in seen)


def test_line_search_passes_over_sizes_that_cannot_be_analysed():
    def residual_at(x):
        return None if np.linalg.norm(x) > 0.1 else np.array([np.linalg.norm(x) - 0.2])

    x, _, chi2 = line_search(residual_at, [0.05, 0.0], [0.0, 0.0], [0.15, 0.15])
    assert np.linalg.norm(x) <= 0.1 and chi2 == pytest.approx((np.linalg.norm(x) - 0.2) ** 2)
    assert line_search(lambda x: None, [0.05, 0.0], [0.0, 0.0], [0.15, 0.15]) is None


def test_a_ray_worse_everywhere_than_the_current_model_gives_size_0():
    """The model r(x) = 1 - 40 x + 400 x^2 predicts r = 0 at x = 0.05; the exact residual is
    1 + x everywhere (chi^2 > 1 = the current one at every x > 0): the line search's best
    point would be worse than leaving the candidate out, so the result is x = 0, chi^2 1 and a
    zero signature. Where the exact residual agrees with the model, its minimum is found."""
    cand = SimpleNamespace(kind="bow", reference=(0.05,), lower=(0.0,), upper=(0.15,))
    s = coefficients([1.0], [[0.0], [1.0]], [0.05])
    out = [(cand, s, None)]
    line_searches(out, np.array([1.0]), lambda c, x: np.array([1.0 + x[0]]), {"bow": "one_sided"})
    _, signature, (size, chi2) = out[0]
    assert size.tolist() == [0.0] and chi2 == 1.0 and not signature.any()
    out = [(cand, s, None)]
    line_searches(out, np.array([1.0]), lambda c, x: np.array([1.0 - 20.0 * x[0]]),
                  {"bow": "one_sided"})
    _, _, (size, chi2) = out[0]
    assert size[0] == pytest.approx(0.05, rel=0.2) and chi2 < 0.05


def test_centred_samples_and_trust_box_by_hand():
    """The centred scheme samples +-2h on each axis and 2h on both, and trusts -2h..2h (within
    the bounds); one parameter r(x) = 1 - 10 x + 100 x^2 = (1 - 5 x)^2 + 75 x^2 from
    r(0.1) = 1 and r(-0.1) = 3: a = (1 - 3) / 0.2 = -10, c = (1 + 3 - 2) / 0.02 = 100."""
    assert sample_points((0.1, 0.3), "centred") == pytest.approx(
        np.array([[0.2, 0.0], [-0.2, 0.0], [0.0, 0.6], [0.0, -0.6], [0.2, 0.6]]))
    lo, hi = trust_box((0.1, 0.3), (-0.3, -0.8), (0.3, 0.5), "centred")
    assert lo.tolist() == pytest.approx([-0.2, -0.6]) and hi.tolist() == pytest.approx([0.2, 0.5])
    s = coefficients([1.0], [[1.0], [3.0]], [0.05], "centred")
    assert s == pytest.approx(np.array([[-10.0, 100.0]]), rel=1e-12)
    x, chi2 = quadratic_fit([1.0], s, [0.05], [-0.3], [0.3], "centred")    # minimum at 0.05
    assert x == pytest.approx([0.05], abs=1e-6) and chi2 == pytest.approx(0.75 ** 2, rel=1e-6)
    # r = 2 - 10 x is zero at 0.2, beyond the trust box: the fit stops at 2h = 0.1
    x, chi2 = quadratic_fit([2.0], np.array([[-10.0, 0.0]]), [0.05], [-0.3], [0.3], "centred")
    assert x == pytest.approx([0.1], abs=1e-8) and chi2 == pytest.approx(1.0, rel=1e-6)
    with pytest.raises(InputError, match="scheme"):
        sample_points((0.1,), "both")
