"""The kernel package's own checks: the unrolled coefficients against the tableaus, and the
argument bundles' field order."""
import numpy as np
import pytest

from nlbeam import _kernels as K
from nlbeam._kernels import codes


def test_the_unrolled_coefficients_equal_the_tableaus():
    codes.check_unrolled()  # also run on import; raises on a mismatch
    got = codes.unrolled_tableaus()
    # every nonzero tableau entry of RK4 and DP5 appears among the unrolled scalars
    for key, want in codes.TABLEAUS.items():
        np.testing.assert_array_equal(np.asarray(got[key]), want)
    # the classical values, independently of both copies
    np.testing.assert_array_equal(K._B_RK4 * 6.0, [1.0, 2.0, 2.0, 1.0])
    assert abs(K._B_DP5.sum() - 1.0) < 1e-15 and abs(K._BH_DP5.sum() - 1.0) < 1e-15
    np.testing.assert_allclose(K._A_DP5.sum(axis=1), K._C_DP5, rtol=0, atol=1e-15)


@pytest.mark.parametrize("key, index", [("A_DP5", (4, 2)), ("e_DP5", (6,)), ("c_RK4", (3,)),
                                        ("A_RK4", (2, 0))])
def test_the_coefficient_check_fires_when_a_tableau_entry_moves(key, index):
    bad = np.array(codes.TABLEAUS[key], dtype=float)
    bad[index] = np.nextafter(bad[index], 1.0) if bad[index] != 1.0 else 0.999
    with pytest.raises(AssertionError, match=rf"{key}\[{', '.join(map(str, index))}\]"):
        codes.check_unrolled({key: bad})


def test_the_coefficient_check_fires_when_a_scalar_moves(monkeypatch):
    monkeypatch.setattr(codes, "_D53", np.nextafter(codes._D53, 0.0))
    with pytest.raises(AssertionError, match=r"A_DP5\[4, 2\]"):
        codes.check_unrolled()
    monkeypatch.undo()
    monkeypatch.setattr(codes, "_RC3", 0.25)
    with pytest.raises(AssertionError, match=r"c_RK4\[2\]"):
        codes.check_unrolled()


def test_the_bundle_builders_follow_the_field_order():
    # the builders return plain tuples in the namedtuples' field order (the kernel names them):
    # one field at a time set to 1, all others 0
    names = K.Settings._fields
    for name in names:
        cfg = K.Settings(*K.settings(**{k: 1 if k == name else 0 for k in names}))
        assert [k for k in names if getattr(cfg, k)] == [name]
    cfg = K.Settings(*K.settings(**dict.fromkeys(names, 1)))
    assert [type(v) for v in cfg] == [int, float, float, float, float, float, float, float, int,
                                      bool, bool, bool, int, bool, bool]
    for bundle, build in ((K.Start, K.start), (K.Outputs, K.outputs)):
        arrays = {name: np.zeros(1) for name in bundle._fields}
        got = bundle(*build(**arrays))
        assert all(getattr(got, k) is v for k, v in arrays.items())
