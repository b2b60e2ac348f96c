"""CasADi functions compiled to C, cached on disk, with an interpreted fallback.

:func:`compiled` takes CasADi functions (SX, or MX whose parts all generate
code) and returns them as ``casadi.external`` functions loaded from a shared
library that CasADi's code generator and the C compiler made (``gcc -O3``
unless ``CC``/``DESIGN_CFLAGS`` say otherwise). The library is kept in a
cache folder (``$DESIGN_CACHE_DIR``, else ``$XDG_CACHE_HOME/grasp-design``,
else ``~/.cache/grasp-design``) under a name that hashes the functions'
serialized forms, CasADi's version, the compiler and its flags, so a second
run (and every later process) loads it without compiling. Compiled and
interpreted functions compute the same operations in the same order: their
outputs agree to rounding (tests/test_compiled.py).

When no compiler is found, or compiling fails, or ``DESIGN_COMPILE=0``, the
functions are returned as they were (interpreted by CasADi's virtual
machine), and :class:`Compiled` says so and why; a design run reports it in
its profile (``profile["compiled"]``), with the libraries :data:`status`
logged as built or loaded during the run.
"""

from __future__ import annotations

import hashlib
import os
import shlex
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import casadi as ca

#: C compiler flags (overridden by $DESIGN_CFLAGS): -O3, no -march=native, so
#: the library's arithmetic is the interpreter's (no fused multiply-adds) and
#: it runs on any machine that shares the cache
DEFAULT_FLAGS = ("-O3", "-fPIC", "-shared")


@dataclass(frozen=True)
class Compiled:
    """:func:`compiled`'s answer: the functions, whether they are the
    compiled ones, and the compiler command or why they are not."""

    functions: list
    compiled: bool
    reason: str
    #: the shared library's path (None: not compiled)
    library: str | None = None


class CompileLog:
    """The libraries :func:`compiled` loaded in this process (built now or
    found in the cache), for a run's profile."""

    def __init__(self):
        self.libraries: list[dict] = []

    def summary(self, since: int = 0) -> dict:
        """The libraries loaded since the ``since``-th, those built among
        them, the wall time building took and the compiler's CPU time (s; in
        child processes, so not in the run's own CPU time), and the cache
        folder."""
        new = self.libraries[since:]
        return {"libraries_loaded": len(new),
                "libraries_built": sum(1 for lib in new if lib["built"]),
                "compile_wall_time_s": sum(lib["compile_s"] for lib in new),
                "compiler_cpu_time_s": sum(lib["compile_cpu_s"] for lib in new),
                "cache": str(cache_dir())}


status = CompileLog()


def cache_dir() -> Path:
    """Where compiled libraries are kept."""
    if os.environ.get("DESIGN_CACHE_DIR"):
        return Path(os.environ["DESIGN_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "grasp-design"


def compiler() -> tuple[list[str] | None, str]:
    """The compiler command and flags, or None with the reason."""
    if os.environ.get("DESIGN_COMPILE", "1") == "0":
        return None, "disabled by DESIGN_COMPILE=0"
    cc = shlex.split(os.environ.get("CC", "gcc"))
    if not cc or shutil.which(cc[0]) is None:
        return None, f"no C compiler: {cc[0] if cc else '(empty CC)'} not found"
    flags = shlex.split(os.environ["DESIGN_CFLAGS"]) if "DESIGN_CFLAGS" in os.environ \
        else list(DEFAULT_FLAGS)
    return cc + flags, ""


def library_key(functions: list[ca.Function], command: list[str], extra: str = "") -> str:
    """Hash of the functions' serialized forms, CasADi's version, the
    compiler command and the C source added to the functions'."""
    h = hashlib.sha256()
    h.update(ca.__version__.encode())
    h.update(" ".join(command).encode())
    for f in functions:
        h.update(f.name().encode())
        h.update(f.serialize().encode())
    h.update(extra.encode())
    return h.hexdigest()[:24]


def compiled(functions: list[ca.Function], extra: str = "") -> Compiled:
    """``functions`` compiled (loaded from the cache, or built into it), or
    the same functions, interpreted, if that is not possible. ``extra``: C
    source compiled after the generated code, into the same library (it may
    call the functions by name; see design/solvers/native_chord.py)."""
    command, reason = compiler()
    if command is None:
        return Compiled(list(functions), False, reason)
    errors = (OSError, RuntimeError, subprocess.SubprocessError)
    try:
        path, built, seconds = _library(functions, command, extra)
        try:
            out = [ca.external(f.name(), str(path)) for f in functions]
        except errors:
            if built:
                raise
            path.unlink(missing_ok=True)        # a cached library that does not load: again
            path, built, seconds = _library(functions, command, extra)
            out = [ca.external(f.name(), str(path)) for f in functions]
    except errors as exc:
        return Compiled(list(functions), False,
                        f"compilation failed: {str(exc).strip()[:300]}")
    status.libraries.append({"path": str(path), "built": built, "compile_s": seconds[0],
                             "compile_cpu_s": seconds[1],
                             "functions": [f.name() for f in functions]})
    return Compiled(out, True, " ".join(command), str(path))


@lru_cache(maxsize=None)
def compiled_once(f: ca.Function) -> ca.Function:
    """``f`` compiled as :func:`compiled` does it, once per process for the
    same function object (a model built again for every run takes its
    functions from a cached transcription)."""
    return compiled([f]).functions[0]


def _library(functions: list[ca.Function], command: list[str], extra: str = ""
             ) -> tuple[Path, bool, tuple[float, float]]:
    """The cached library's path, whether it was built now, and the wall
    time and the compiler's CPU time (s) building it took."""
    key = library_key(functions, command, extra)
    folder = cache_dir()
    path = folder / f"casadi_{key}.so"
    if path.exists():
        return path, False, (0.0, 0.0)
    folder.mkdir(parents=True, exist_ok=True)
    t0, children = time.perf_counter(), _children_cpu()
    with tempfile.TemporaryDirectory(dir=folder, prefix="build_") as tmp:
        name = f"casadi_{key}"
        gen = ca.CodeGenerator(f"{name}.c", {"with_header": False})
        for f in functions:
            gen.add(f)
        source = Path(gen.generate(tmp + os.sep))
        if extra:
            with open(source, "a") as out:
                out.write(extra)
        target = Path(tmp) / f"{name}.so"
        done = subprocess.run([*command, str(source), "-o", str(target), "-lm"],
                              capture_output=True, text=True)
        if done.returncode != 0:
            raise RuntimeError(f"{command[0]} exited with {done.returncode}: {done.stderr}")
        # atomic: a concurrent process either sees no library or a whole one
        os.replace(target, path)
    return path, True, (time.perf_counter() - t0, _children_cpu() - children)


def _children_cpu() -> float:
    """CPU time (s) of this process's finished child processes (the compiler:
    not in the process's own process_time)."""
    t = os.times()
    return t.children_user + t.children_system
