"""Fit report and plot details of the new-user report: one identifiability note per group of
estimates (defect 13), a zero final estimate drawn ending at 0 % in the convergence panel
(defect 12)."""

import numpy as np

from estimate.fitting.identifiability import analyse
from estimate.fitting.plots import trajectory_change


def test_two_weak_directions_of_one_pair_give_one_note_with_the_weakest():
    # two estimates, both directions weak (relative std 0.03 and 0.08), each shared half
    # and half: before, the pair was reported twice with different numbers
    c, s = np.cos(np.pi / 4), np.sin(np.pi / 4)
    rot = np.array([[c, -s], [s, c]])
    cov = rot @ np.diag([0.03**2, 0.08**2]) @ rot.T
    ident = analyse(cov, np.ones(2), ("p1.length", "fixed.mass"))
    assert len(ident.groups) == 1 and set(ident.groups[0]) == {"p1.length", "fixed.mass"}
    assert ident.evidence == ("relative standard deviation 0.08 along their joint direction",)


def test_distinct_groups_are_all_kept():
    cov = np.diag([0.05, 0.05, 0.05, 0.05]) ** 2
    cov[0, 1] = cov[1, 0] = 0.9 * 0.05**2
    cov[2, 3] = cov[3, 2] = 0.9 * 0.05**2
    ident = analyse(cov, np.ones(4), ("a", "b", "c", "d"))
    assert sorted(map(sorted, ident.groups)) == [["a", "b"], ["c", "d"]]


def test_a_zero_final_estimate_ends_at_zero_percent():
    history = np.array([[1.2, 0.018, 5.0], [1.1, 0.005, 4.0], [1.0, 0.0, 4.0]])
    change, zero = trajectory_change(history, history[-1])
    assert zero.tolist() == [False, True, False]
    # by hand: (h - final) / final, and for the zero estimate over its largest value 0.018
    assert np.allclose(change[:, 0], [20.0, 10.0, 0.0])
    assert np.allclose(change[:, 1], [100.0, 100 * 0.005 / 0.018, 0.0])
    assert np.allclose(change[:, 2], [25.0, 0.0, 0.0])
    assert change[-1].tolist() == [0.0, 0.0, 0.0]  # was -100 % for the zero estimate
