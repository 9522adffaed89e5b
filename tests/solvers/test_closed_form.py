"""The closed forms round the same on every Python: sums left to right, as the compiled core
sums (CPython 3.12+ ``sum()`` of floats is Neumaier-compensated, so it rounds differently and
the two paths, bit-identical on 3.11, parted on 3.13; issue 20)."""

from __future__ import annotations

import numpy as np

from pinrate.solvers import closed_form, conditioning

BIG = 2.0**53
"""BIG + 1 rounds to BIG in float64: (BIG + 1) - BIG is 0 left to right, 1 compensated."""


def test_the_schur_complement_sums_left_to_right() -> None:
    # A - B W^-1 U with W = I: entry (0, 0) is A00 - (BIG*1 + 1*1 + (-BIG)*1). Left to right
    # the bracket is (BIG + 1) - BIG = 0 in float64, so the complement is A itself and the arm
    # rate is v / 1; a compensated sum gives 1, a complement of 0: singular.
    A = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    B = [[BIG, 1.0, -BIG], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
    U = [[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
    W = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    assert (BIG + 1.0) - BIG == 0.0
    arm, _ = closed_form.schur(A, B, U, W, [1.0, 2.0, 3.0], [0.0, 0.0, 0.0])
    assert arm == [1.0, 2.0, 3.0]


def test_the_condition_bound_sums_left_to_right() -> None:
    # ||M||_F^2 with squares 2^54 and eight 1s: left to right each +1 is lost (the spacing of
    # floats at 2^54 is 4), so the sum is 2^54; compensated it is 2^54 + 8, which moves the
    # bound by one unit in the last place.
    M = [[2.0**27, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0]]
    identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    assert 2.0**54 + 1.0 == 2.0**54
    assert 1.0 / np.sqrt(2.0**54 * 3.0) != 1.0 / np.sqrt((2.0**54 + 8.0) * 3.0)  # the test can fail
    assert conditioning.inverse_condition_bound(M, identity) == 1.0 / np.sqrt(2.0**54 * 3.0)
