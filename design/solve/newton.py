"""CasADi Newton rootfinders on R(z, q) = 0, built once per setting."""

from __future__ import annotations

import casadi as ca


class NewtonCache:
    """Rootfinders (z0, q) -> z of one residual, by (tolerance, max_iter,
    error_on_fail): Newton with line search; ``error_on_fail`` raises instead
    of returning the last iterate (inside an NLP, where Ipopt then shortens
    its step)."""

    def __init__(self, name: str, residual: ca.Function, linear_solver: str):
        self.name, self.residual, self.linear_solver = name, residual, linear_solver
        self._built: dict = {}

    def get(self, tolerance: float, max_iter: int, error_on_fail: bool) -> ca.Function:
        key = (tolerance, max_iter, error_on_fail)
        if key not in self._built:
            self._built[key] = ca.rootfinder(
                self.name, "newton", self.residual,
                {"abstol": tolerance, "max_iter": max_iter, "error_on_fail": error_on_fail,
                 "line_search": True, "linear_solver": self.linear_solver,
                 "show_eval_warnings": False})
        return self._built[key]
