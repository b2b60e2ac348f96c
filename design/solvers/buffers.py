"""Evaluating a CasADi function on numpy arrays through its buffer interface.

``Function.__call__`` converts each numpy input to a DM and each output back
to numpy element by element; for a 1000-load sweep's arrays that takes
longer than the compiled evaluation itself, and for an integrator's trial
contact solve it is half the call (``python -m benchmarks.beam_sweep`` and
``benchmarks.grasp`` time both paths' users). ``Function.buffer`` reads and
writes caller-owned memory instead.
"""

from __future__ import annotations

import casadi as ca
import numpy as np


class Buffered:
    """``f`` called on numeric inputs of its (dense) input shapes through one
    buffer kept for all calls; returns fresh float arrays of its (dense)
    output shapes. Not for concurrent calls from several threads."""

    def __init__(self, f: ca.Function):
        self.name = f.name()
        for i in range(f.n_in()):
            if not f.sparsity_in(i).is_dense():
                raise ValueError(f"{self.name}: input {i} is sparse")
        for i in range(f.n_out()):
            if not f.sparsity_out(i).is_dense():
                raise ValueError(f"{self.name}: output {i} is sparse")
        self._buffer, self._run = f.buffer()
        self._inputs = [np.empty(f.nnz_in(i)) for i in range(f.n_in())]
        self._outputs = [np.empty(f.nnz_out(i)) for i in range(f.n_out())]
        self._shapes = [f.size_out(i) for i in range(f.n_out())]
        for i, a in enumerate(self._inputs):
            self._buffer.set_arg(i, memoryview(a))
        for i, out in enumerate(self._outputs):
            self._buffer.set_res(i, memoryview(out))

    @property
    def inputs(self) -> list[np.ndarray]:
        """The buffer's inputs (flat, column-major): fill them, then :meth:`run`."""
        return self._inputs

    def run(self) -> list[np.ndarray]:
        """Evaluate on :attr:`inputs` as they stand; the outputs (flat,
        column-major) are views of the buffer, overwritten by the next call:
        the fast path for a loop that reuses most inputs and consumes each
        output at once."""
        self._run()
        if self._buffer.ret() != 0:
            raise RuntimeError(f"{self.name} failed (return code {self._buffer.ret()})")
        return self._outputs

    def __call__(self, *args) -> list[np.ndarray]:
        for i, (buf, a) in enumerate(zip(self._inputs, args)):
            a = np.asarray(a, dtype=float).ravel(order="F")
            if a.size != buf.size:
                raise ValueError(f"{self.name}: input {i} has {a.size} values, needs {buf.size}")
            buf[:] = a
        self._run()
        if self._buffer.ret() != 0:
            raise RuntimeError(f"{self.name} failed (return code {self._buffer.ret()})")
        return [out.reshape(shape, order="F").copy()
                for out, shape in zip(self._outputs, self._shapes)]


def evaluate(f: ca.Function, *args: np.ndarray) -> list[np.ndarray]:
    """``f``'s outputs for numeric inputs of its (dense) input shapes, as
    float arrays of its (dense) output shapes (a buffer for this call only)."""
    return Buffered(f)(*args)
