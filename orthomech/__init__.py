"""orthomech from Python: planar linkage analysis with the mass-orthogonal projection method.

Each analysis is the command line's subcommand of the same name, run in this process by the same
code (the compiled part, ``_orthomech``, links the library and the CLI): the result is the CLI's
``--json`` document, with the same names, as dicts, lists and NumPy arrays (a list of numbers is
a 1-D array, a list of equally long lists of numbers a 2-D array; a JSON ``null`` among numbers
is NaN)::

    import orthomech
    r = orthomech.cycle("mechanisms/crank-rocker.yaml", steps=72)
    r["peaks"]["drive"]["peak"]

A mechanism is a file path, YAML text, or a :class:`Mechanism` from :func:`load`. Options are the
subcommand's command-line options (docs/cli.md) as keywords: ``t_end=2`` is ``--t-end=2``, a
``True`` flag is given, ``False``/``None`` left out, a list repeats the option, ``set`` also
takes a dict (``set={"L": 120}`` is ``--set L=120``), and a Python keyword takes a trailing
underscore (``from_="90deg"`` is ``--from=90deg``). Each function's docstring ends with its
command's ``--help``. Calls run one at a time (the global interpreter lock is held).

Errors are exceptions named after the CLI's exit codes: :class:`InputError` (2: bad file or
option; ``file``, ``line``, ``column`` of the problem), :class:`CheckFailed` (1: an analysis ran
and a check failed; its message names the failed checks), :class:`NumericalError` (3),
:class:`InternalError` (4), :class:`Stopped` (5: a run stopped at its step budget, time limit or
an interrupt, with what it computed). The result of an analysis that ran (``validate`` that found
a problem, ``simulate`` that stopped at a change point or at its budget) is the exception's
``result``. The CLI's warnings are Python warnings (:class:`OrthomechWarning`, through
:mod:`warnings`); its other log lines go to ``sys.stderr``.
"""

from __future__ import annotations

import glob
import importlib.util
import json
import os
import re
import sys
import warnings

import numpy as np


def _load_core():
    try:
        from . import _orthomech  # installed, or the build tree (PYTHONPATH=build/python)

        return _orthomech
    except ImportError:
        pass
    # The package's source (orthomech/ at the top of the repository): the compiled part is in
    # the build tree, $ORTHOMECH_BUILD_DIR or build/ next to this folder.
    here = os.path.dirname(os.path.abspath(__file__))
    build = os.environ.get("ORTHOMECH_BUILD_DIR", os.path.join(here, os.pardir, "build"))
    found = sorted(glob.glob(os.path.join(build, "python", "orthomech", "_orthomech*.so")))
    if not found:
        raise ImportError(
            "orthomech: the compiled module _orthomech is not built; run scripts/build "
            "(or set ORTHOMECH_BUILD_DIR to the build folder)"
        )
    spec = importlib.util.spec_from_file_location(__name__ + "._orthomech", found[0])
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    sys.modules[spec.name] = module
    return module


_core = _load_core()

__version__ = _core.version
git_revision = _core.git_revision

__all__ = [
    "Mechanism",
    "load",
    "info",
    "cycle",
    "simulate",
    "assemble",
    "validate",
    "crosscheck",
    "command",
    "Error",
    "InputError",
    "CheckFailed",
    "NumericalError",
    "InternalError",
    "Stopped",
    "OrthomechWarning",
]


# ---- Errors: one type per exit code (docs/cli.md) ----------------------------------------------


class Error(Exception):
    """An orthomech command failed: ``exit_code`` (the CLI's), ``message`` (its stderr),
    ``result`` (the JSON document, when the analysis ran), ``file``/``line``/``column`` when the
    message names a place in a mechanism file."""

    exit_code = None

    def __init__(self, message, exit_code=None, result=None, file=None, line=None, column=None):
        super().__init__(message)
        self.message = message
        if exit_code is not None:
            self.exit_code = exit_code
        self.result = result
        self.file, self.line, self.column = file, line, column


class CheckFailed(Error):
    """Exit code 1: an analysis ran and a check failed (``result`` holds it)."""

    exit_code = 1


class InputError(Error, ValueError):
    """Exit code 2: a bad mechanism file or option (``file``, ``line``, ``column``)."""

    exit_code = 2


class NumericalError(Error, ArithmeticError):
    """Exit code 3: cannot assemble, singular, no convergence."""

    exit_code = 3


class InternalError(Error, RuntimeError):
    """Exit code 4: a bug, please report it."""

    exit_code = 4


class Stopped(Error):
    """Exit code 5: a run stopped at a bound before its end (its step budget, ``time_limit``, or
    SIGINT/SIGTERM); ``result`` holds what it computed (``complete`` is false, ``stop`` says
    which bound)."""

    exit_code = 5


class OrthomechWarning(UserWarning):
    """A warning of the CLI (a ``warning: ...`` line of its log), raised through :mod:`warnings`
    so that ``warnings.simplefilter("error", orthomech.OrthomechWarning)`` and pytest see it."""


_ERRORS = {1: CheckFailed, 2: InputError, 3: NumericalError, 4: InternalError, 5: Stopped}
# "file:line:column: ..." (the reader's messages), possibly after the log level ("error: ").
_PLACE = re.compile(r"^(?:[a-z]+: )?(?P<file>[^\n:]+):(?P<line>\d+):(?P<column>\d+)", re.M)


def _failed_checks(subcommand, result):
    """The failed checks of a report, in words (the message of CheckFailed, whose CLI prints
    the report rather than an error)."""
    if not isinstance(result, dict):
        return ""
    words = []
    for p in result.get("positions", []) or []:  # validate
        if isinstance(p, dict) and not p.get("pass", True):
            words.append(f"position '{p.get('name')}': " + "; ".join(p.get("failures", [])))
    for d in result.get("defects", []) or []:
        if not any(str(d) in w for w in words):  # a position's failure names it already
            words.append(str(d))
    for c in result.get("checks", []) or []:  # crosscheck
        if isinstance(c, dict) and not c.get("pass", True):
            words.append(f"{c.get('name')} differs by {c.get('max_relative')}")
    if not words and result.get("message"):  # cycle: stopped at a dead point
        words.append(str(result["message"]))
    return f"orthomech {subcommand}: " + ("; ".join(words) if words else "a check failed")


def _error(code, message, result, subcommand=""):
    cls = _ERRORS.get(code, Error)
    m = _PLACE.search(message)
    place = (m["file"], int(m["line"]), int(m["column"])) if m else (None, None, None)
    if not message and code == 1:
        message = _failed_checks(subcommand, result)
    return cls(message or f"orthomech: exit code {code}", code, result, *place)


def _log(err):
    """The CLI's log: ``warning: ...`` lines as Python warnings, the others to sys.stderr."""
    rest = []
    for line in err.splitlines(keepends=True):
        if line.startswith("warning: "):
            warnings.warn(line[len("warning: "):].rstrip("\n"), OrthomechWarning, stacklevel=3)
        else:
            rest.append(line)
    if rest:
        sys.stderr.write("".join(rest))


# ---- Mechanisms --------------------------------------------------------------------------------

TEXT_ORIGIN = "<string>"


class Mechanism:
    """A mechanism file (``path``) or YAML text (``text``; messages name it ``origin``),
    checked by :func:`load`."""

    def __init__(self, path=None, text=None, origin=TEXT_ORIGIN):
        if (path is None) == (text is None):
            raise TypeError("Mechanism: give either path or text")
        if path is not None and "\0" in os.fsdecode(os.fspath(path)):
            # The C++ side would cut the name at the NUL and read another file.
            raise InputError(f"{os.fsdecode(os.fspath(path))!r}: file: the path holds a NUL "
                             "character", 2)
        self.path = None if path is None else os.fspath(path)
        self.text = text
        self.origin = self.path if self.path is not None else origin

    def __repr__(self):
        if self.path is not None:
            return f"Mechanism(path={self.path!r})"
        return f"Mechanism(text=<{len(self.text)} characters>, origin={self.origin!r})"


def _is_text(source: str) -> bool:
    return "\n" in source or (":" in source and not os.path.exists(source))


def _mechanism(source) -> Mechanism:
    if isinstance(source, Mechanism):
        return source
    if isinstance(source, os.PathLike):
        return Mechanism(path=source)
    if isinstance(source, str):
        return Mechanism(text=source) if _is_text(source) else Mechanism(path=source)
    raise TypeError(f"a mechanism is a file path, YAML text or a Mechanism, not {type(source)}")


def load(source, origin: str = TEXT_ORIGIN) -> Mechanism:
    """A mechanism from a file path or YAML text, read and checked as the CLI reads a file:
    :class:`InputError` (with ``file``, ``line``, ``column``) when it is not valid."""
    m = _mechanism(source)
    if m.path is None and origin != TEXT_ORIGIN:
        m = Mechanism(text=m.text, origin=origin)
    if m.path is not None:
        try:
            with open(m.path, encoding="utf-8") as f:
                text = f.read()
        except OSError as e:
            raise InputError(f"{m.path}: file: cannot open the file: {e.strerror}", 2,
                             file=m.path) from None
    else:
        text = m.text
    problem = _core.check(text, m.origin)
    if problem is not None:
        message, file, line, column = problem
        raise InputError(message, 2, None, file, line or None, column or None)
    return m


# ---- Running a subcommand ----------------------------------------------------------------------


def _number(v):
    return repr(float(v)) if isinstance(v, float) else str(v)


def _options(options: dict) -> list:
    args = []
    for key, value in options.items():
        flag = "--" + key.rstrip("_").replace("_", "-")
        if value is None or value is False:
            continue
        if value is True:
            args.append(flag)
            continue
        if key == "set" and isinstance(value, dict):
            value = [f"{k}={_number(v)}" for k, v in value.items()]
        values = value if isinstance(value, (list, tuple)) else [value]
        for v in values:
            if isinstance(v, (list, tuple)):  # --velocity b=0,1 as ("b", (0, 1))? keep text
                v = ",".join(_number(x) for x in v)
            args.append(f"{flag}={_number(v) if not isinstance(v, str) else v}")
    return args


def command(args, mechanism=None):
    """Runs ``orthomech ARGS...`` in this process: (exit code, stdout, stderr). With
    ``mechanism`` given as text, the argument equal to its origin reads the text."""
    for a in args:
        if "\0" in str(a):  # the C++ side would cut the argument at the NUL
            raise InputError(f"{str(a)!r}: an argument holds a NUL character", 2)
    m = None if mechanism is None else _mechanism(mechanism)
    if m is None or m.path is not None:
        return _core.run([str(a) for a in args])
    return _core.run([str(a) for a in args], m.origin, m.text)


def _run(subcommand, mechanism, options, arrays=True):
    m = _mechanism(mechanism)
    if m.path is None and (options.get("write") or options.get("in_place")):
        raise InputError("assemble: --write and --in-place need a mechanism file, not text", 2)
    args = [subcommand, m.origin, "--json", *_options(options)]
    code, out, err = command(args, m)
    result = None
    if out.strip():
        result = json.loads(out)
        if arrays:
            result = to_arrays(result)
    if code != 0:
        raise _error(code, err.strip(), result, subcommand)
    if err:
        _log(err)
    return result


def info(mechanism, **options):
    """``orthomech info FILE --json``: structure and mobility."""
    return _run("info", mechanism, options)


def cycle(mechanism, **options):
    """``orthomech cycle FILE --json``: drive and joint reactions over one cycle."""
    return _run("cycle", mechanism, options)


def simulate(mechanism, **options):
    """``orthomech simulate FILE --json`` (``t_end=`` is required): forward dynamics."""
    return _run("simulate", mechanism, options)


def assemble(mechanism, **options):
    """``orthomech assemble FILE --json``: the assembled design position."""
    return _run("assemble", mechanism, options)


def validate(mechanism, **options):
    """``orthomech validate FILE --json``: the design positions report (a failed check raises
    :class:`CheckFailed` with the report as ``result``)."""
    return _run("validate", mechanism, options)


def crosscheck(mechanism, **options):
    """``orthomech crosscheck FILE --json``: dual against primal formulation."""
    return _run("crosscheck", mechanism, options)


def _with_cli_help(function):
    """The subcommand's `--help` (its options) under the function's own docstring."""
    code, out, _ = _core.run([function.__name__, "--help"])
    if code == 0 and out:
        function.__doc__ = f"{function.__doc__}\n\nThe command line's help (options as keywords):\n\n{out}"
    return function


for _f in (info, cycle, simulate, assemble, validate, crosscheck):
    _with_cli_help(_f)
del _f


# ---- JSON to NumPy and back --------------------------------------------------------------------


def _is_number(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _array(values):
    """A list of numbers (or nulls) as a 1-D array, of such equally long lists as 2-D; else
    None."""
    if not values:
        return None
    if all(_is_number(x) or x is None for x in values):
        if all(x is None for x in values):
            return None
        if all(isinstance(x, int) for x in values):
            return np.array(values, dtype=np.int64)
        return np.array([np.nan if x is None else x for x in values], dtype=np.float64)
    if all(isinstance(x, list) for x in values):
        rows = [_array(x) for x in values]
        if all(r is not None and r.ndim == 1 for r in rows) and len({len(r) for r in rows}) == 1:
            return np.array(rows)
    return None


def to_arrays(value):
    """The JSON document with its numeric lists as NumPy arrays (what the analyses return)."""
    if isinstance(value, dict):
        return {k: to_arrays(v) for k, v in value.items()}
    if isinstance(value, list):
        a = _array(value)
        return a if a is not None else [to_arrays(v) for v in value]
    return value


def to_json(value):
    """The inverse of :func:`to_arrays`: arrays as lists, NaN as None (JSON's null)."""
    if isinstance(value, dict):
        return {k: to_json(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return to_json(value.tolist())
    if isinstance(value, list):
        return [to_json(v) for v in value]
    if isinstance(value, float) and value != value:
        return None
    return value
