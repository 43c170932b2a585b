"""The numeric evaluation of the tuning kernels over many frequencies (ColumnMap) against
casadi's own call of the mapped kernel."""

import casadi as ca
import numpy as np
import pytest
from numpy.testing import assert_array_equal

from servotune.tuning.nlp import ColumnMap


def _kernel():
    u, d = ca.SX.sym("u", 3), ca.SX.sym("d", 5)
    out = ca.vertcat(ca.sin(u[0] * d[0]) + u[1] ** 2 * d[1], ca.exp(u[2] * d[2]) * d[4] - d[3])
    return ca.Function("kernel", [u, d], [out])


@pytest.mark.parametrize("n", [1, 7, 16, 17, 100])
@pytest.mark.parametrize("buffered", [True, False])
def test_column_map_equals_the_plain_call_of_the_mapped_kernel(n, buffered):
    # chunks of 16 columns: sizes below, at and across a chunk boundary; the plain path is
    # what casadi versions without Function.buffer take
    kernel = _kernel()
    rng = np.random.default_rng(n)
    data, u = rng.normal(size=(5, n)), rng.normal(size=3)
    column_map = ColumnMap(kernel, chunk=16)
    if not buffered:
        column_map._run = None
    want = np.array(kernel.map(n)(u, data))
    assert_array_equal(column_map(u, data), want)
    # a second call with other values reuses the buffers
    assert_array_equal(column_map(-u, 2 * data), np.array(kernel.map(n)(-u, 2 * data)))


def test_column_map_rejects_data_of_the_wrong_height():
    with pytest.raises(ValueError, match="5 data rows"):
        ColumnMap(_kernel(), chunk=4)(np.zeros(3), np.zeros((4, 3)))
