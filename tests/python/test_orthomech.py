"""The Python module against the CLI (issue 16): every analysis returns the CLI's --json document
(the oracle: the built executable, run as a separate process), errors are the exit codes'
exception types with file:line:column. Run by ctest (Package.Python) with Debian's Python."""

import json
import os
import re
import subprocess
import sys
import warnings

import numpy as np
import pytest

import orthomech

SOURCE = os.environ.get("ORTHOMECH_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
CLI = os.environ.get("ORTHOMECH_CLI", os.path.join(SOURCE, "build", "orthomech"))
MECH = os.path.join(SOURCE, "mechanisms")
CRANK_ROCKER = os.path.join(MECH, "crank-rocker.yaml")


def cli(*args):
    """The executable's (exit code, JSON document or None, stderr)."""
    p = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True)
    return p.returncode, (json.loads(p.stdout) if p.stdout.strip() else None), p.stderr


def cli_json(*args):
    code, doc, err = cli(*args)
    assert code == 0, err
    return doc


# ---- Results equal the CLI's JSON ---------------------------------------------------------------

CASES = [
    ("info", "crank-rocker.yaml", {}, []),
    ("info", "slider-crank.yaml", {"units": "si"}, ["--units", "si"]),
    ("cycle", "crank-rocker.yaml", {"steps": 72}, ["--steps", "72"]),
    ("cycle", "slider-crank.yaml", {"steps": 40, "positions": True}, ["--steps", "40", "--positions"]),
    ("assemble", "crank-rocker.yaml", {}, []),
    ("validate", "crank-rocker.yaml", {}, []),
    ("simulate", "pendulum.yaml", {"t_end": 0.5}, ["--t-end", "0.5"]),
    ("crosscheck", "crank-rocker.yaml", {"samples": 5}, ["--samples", "5"]),
]


@pytest.mark.parametrize("command,file,options,args", CASES, ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_result_equals_cli_json(command, file, options, args):
    path = os.path.join(MECH, file)
    result = getattr(orthomech, command)(path, **options)
    assert orthomech.to_json(result) == cli_json(command, path, "--json", *args)


def test_numbers_are_numpy_arrays():
    r = orthomech.cycle(CRANK_ROCKER, steps=36, positions=True)
    velocity = r["points"][0]["bodies"]["crank"]["velocity"]
    assert isinstance(velocity, np.ndarray) and velocity.dtype == np.float64
    assert velocity.shape == (3,)
    assert isinstance(r["points"], list) and len(r["points"]) == 36  # objects stay dicts
    assert isinstance(r["peaks"]["drive"]["peak"], float)
    s = orthomech.simulate(os.path.join(MECH, "pendulum.yaml"), t_end=0.2)
    kinetic = s["samples"]["kinetic"]
    assert isinstance(kinetic, np.ndarray) and kinetic.ndim == 1 and len(kinetic) > 2
    assert isinstance(s["samples"]["t"], np.ndarray)
    # Back to the document: the same values (the CLI's, compared in the tests above).
    assert orthomech.to_json(s)["samples"]["kinetic"] == kinetic.tolist()


def test_nulls_and_matrices():
    r = orthomech.to_arrays({"a": [1, None, 2.5], "m": [[1, 2], [3, 4]], "k": [1, 2],
                             "mixed": [1, "x"], "objects": [{"v": [0.5]}], "empty": []})
    assert np.isnan(r["a"][1]) and r["a"][2] == 2.5
    assert r["m"].shape == (2, 2) and r["k"].dtype == np.int64
    assert r["mixed"] == [1, "x"] and r["empty"] == []
    assert isinstance(r["objects"][0]["v"], np.ndarray)
    assert orthomech.to_json(r)["a"] == [1.0, None, 2.5]


def test_set_is_the_command_lines():
    doc = cli_json("cycle", CRANK_ROCKER, "--json", "--steps", "36", "--set", "drivers.motor.speed=600rpm")
    for s in ({"drivers.motor.speed": "600rpm"}, ["drivers.motor.speed=600rpm"]):
        r = orthomech.cycle(CRANK_ROCKER, steps=36, set=s)
        assert orthomech.to_json(r) == doc
    nominal = orthomech.cycle(CRANK_ROCKER, steps=36)
    assert r["peaks"]["drive"]["peak"] != nominal["peaks"]["drive"]["peak"]


def test_yaml_text_is_the_file():
    with open(CRANK_ROCKER, encoding="utf-8") as f:
        text = f.read()
    doc = cli_json("cycle", CRANK_ROCKER, "--json", "--steps", "36")
    for source in (text, orthomech.load(text)):
        r = orthomech.to_json(orthomech.cycle(source, steps=36))
        assert r.pop("file") == "<string>"
        assert r == {k: v for k, v in doc.items() if k != "file"}
    m = orthomech.load(CRANK_ROCKER)
    assert m.path == CRANK_ROCKER
    assert orthomech.to_json(orthomech.cycle(m, steps=36)) == doc


def test_version_is_the_clis():
    out = subprocess.run([CLI, "--version"], capture_output=True, text=True).stdout.strip()
    assert out.startswith(f"orthomech {orthomech.__version__}")
    assert orthomech.git_revision in out


# ---- Errors -----------------------------------------------------------------------------------


def broken_text():
    with open(CRANK_ROCKER, encoding="utf-8") as f:
        lines = f.read().splitlines()
    n = next(i for i, l in enumerate(lines) if l.strip() == "mass: 0.03")
    lines[n] = lines[n].replace("0.03", "-1")
    return "\n".join(lines) + "\n", n + 1, lines[n].index("-1") + 1


def test_input_error_carries_file_line_column():
    text, line, column = broken_text()
    with pytest.raises(orthomech.InputError) as e:
        orthomech.load(text)
    assert (e.value.file, e.value.line, e.value.column) == ("<string>", line, column)
    assert e.value.exit_code == 2
    assert isinstance(e.value, ValueError)
    # The same from an analysis, with the CLI's message for the same text in a file.
    with pytest.raises(orthomech.InputError) as a:
        orthomech.info(text)
    assert (a.value.file, a.value.line, a.value.column) == ("<string>", line, column)
    assert f"<string>:{line}:{column}:" in str(a.value)


def test_input_error_of_a_file_is_the_clis(tmp_path):
    text, line, column = broken_text()
    path = tmp_path / "broken.yaml"
    path.write_text(text)
    code, _, err = cli("info", path, "--json")
    assert code == 2
    with pytest.raises(orthomech.InputError) as e:
        orthomech.info(str(path))
    assert str(e.value) == err.strip()
    assert (e.value.file, e.value.line, e.value.column) == (str(path), line, column)
    with pytest.raises(orthomech.InputError):
        orthomech.load(path)


def test_bad_option_is_input_error():
    with pytest.raises(orthomech.InputError) as e:
        orthomech.cycle(CRANK_ROCKER, no_such_option=3)
    assert "no-such-option" in str(e.value)
    with pytest.raises(orthomech.InputError):
        orthomech.cycle(CRANK_ROCKER, steps=-3)


def test_missing_file_is_input_error():
    with pytest.raises(orthomech.InputError) as e:
        orthomech.info(os.path.join(MECH, "no-such-file.yaml"))
    assert "no such file" in str(e.value)


def test_check_failed_carries_the_report():
    path = os.path.join(SOURCE, "tests", "data", "validate", "crank-rocker-circuit-defect.yaml")
    code, doc, _ = cli("validate", path, "--json")
    assert code == 1
    with pytest.raises(orthomech.CheckFailed) as e:
        orthomech.validate(path)
    assert e.value.exit_code == 1
    assert orthomech.to_json(e.value.result) == doc
    # The message names what failed (it was only "orthomech: exit code 1"): the defects and the
    # failures of the report itself (the oracle: the CLI's JSON document).
    assert str(e.value).startswith("orthomech validate: ")
    for d in doc["defects"]:
        assert d in str(e.value)


# A four-bar whose links (1 + 2 + 3 < 10) cannot close (tests/unit/cli/assemble_cli_test.cpp).
SHORT_FOUR_BAR = """orthomech: 1
name: short
ground:
  points: {A0: [0, 0], B0: [10, 0]}
bodies:
  - {name: crank, mass: 1, inertia: 0.1, pose: [0, 0, 0.5], points: {A0: [0, 0], A: [1, 0]}}
  - {name: coupler, mass: 1, inertia: 0.1, pose: [1, 0, 0.2], points: {A: [0, 0], B: [2, 0]}}
  - {name: rocker, mass: 1, inertia: 0.1, pose: [10, 0, 2.5], points: {B0: [0, 0], B: [3, 0]}}
joints:
  - {name: A0, type: revolute, connects: [ground.A0, crank.A0]}
  - {name: A, type: revolute, connects: [crank.A, coupler.A]}
  - {name: B, type: revolute, connects: [coupler.B, rocker.B]}
  - {name: B0, type: revolute, connects: [rocker.B0, ground.B0]}
"""


def test_numerical_error_is_exit_code_3(tmp_path):
    path = tmp_path / "short.yaml"
    path.write_text(SHORT_FOUR_BAR)
    code, doc, err = cli("assemble", path, "--json")
    assert code == 3, (code, err)
    with pytest.raises(orthomech.NumericalError) as e:
        orthomech.assemble(str(path))
    assert e.value.exit_code == 3
    assert isinstance(e.value, ArithmeticError)
    assert str(e.value) == err.strip() and "cannot close" in str(e.value)
    assert orthomech.to_json(e.value.result) == doc
    with pytest.raises(orthomech.NumericalError):  # the same as text
        orthomech.assemble(SHORT_FOUR_BAR)


def test_exception_types():
    assert issubclass(orthomech.InternalError, orthomech.Error)
    assert issubclass(orthomech.Stopped, orthomech.Error)
    assert {c.exit_code for c in (orthomech.CheckFailed, orthomech.InputError,
                                   orthomech.NumericalError, orthomech.InternalError,
                                   orthomech.Stopped)} == {1, 2, 3, 4, 5}


def test_warnings_are_python_warnings(capsys):
    text = open(CRANK_ROCKER, encoding="utf-8").read()
    # A crank 2 mm longer than drawn: the start position moves (a warning), the cycle runs.
    with pytest.warns(orthomech.OrthomechWarning):
        orthomech.cycle(text, steps=12, set={"bodies.crank.points.A": "[32, 0]"})
    assert "warning" not in capsys.readouterr().err  # not printed besides
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # quiet: no warning at all
        orthomech.cycle(text, steps=12, set={"bodies.crank.points.A": "[32, 0]"}, quiet=True)
    assert capsys.readouterr().err == ""


def test_a_stopped_simulation_is_stopped_with_its_samples():
    with pytest.raises(orthomech.Stopped) as e:
        orthomech.simulate(os.path.join(MECH, "pendulum.yaml"), t_end=10, max_steps=40)
    assert e.value.exit_code == 5
    assert e.value.result["complete"] is False and e.value.result["stop"] == "budget"
    assert e.value.result["steps"] == 40


def test_nul_in_a_path_is_an_input_error():
    with pytest.raises(orthomech.InputError) as e:
        orthomech.info(os.path.join(MECH, "pendulum.yaml") + "\0.txt")
    assert "NUL" in str(e.value)


def test_cyclic_alias_in_a_set_value_is_an_input_error():
    # It crashed the interpreter (unbounded recursion over the value's nodes).
    with pytest.raises(orthomech.InputError) as e:
        orthomech.info(CRANK_ROCKER, set=["x={a: &a [*a]}"])
    assert "holds itself" in str(e.value)


# ---- The example script ---------------------------------------------------------------------


def source_tree_env():
    """The environment of a user in the repository: no PYTHONPATH; the package's code is
    orthomech/ at the top, its compiled part in this build (ORTHOMECH_BUILD_DIR)."""
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)
    compiled = os.path.abspath(orthomech._core.__file__)  # BUILD/python/orthomech/_orthomech*.so
    env["ORTHOMECH_BUILD_DIR"] = os.path.dirname(os.path.dirname(os.path.dirname(compiled)))
    return env


def test_done_when_command_in_the_repository():
    code = ("import orthomech; print(orthomech.__file__); "
            "print(repr(orthomech.cycle('mechanisms/crank-rocker.yaml')['peaks']['drive']['peak']))")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=SOURCE,
                       env=source_tree_env())
    assert p.returncode == 0, p.stderr
    file, peak = p.stdout.split()
    assert os.path.samefile(file, os.path.join(SOURCE, "orthomech", "__init__.py"))
    assert float(peak) == cli_json("cycle", CRANK_ROCKER, "--json")["peaks"]["drive"]["peak"]


def test_sweep_example_writes_png(tmp_path):
    out = tmp_path / "sweep.png"
    script = os.path.join(SOURCE, "examples", "python", "sweep_link_length.py")
    p = subprocess.run([sys.executable, script, "--points", "5", "--steps", "36", "--out", str(out)],
                       capture_output=True, text=True, cwd=tmp_path, env=source_tree_env())
    assert p.returncode == 0, p.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # Its variant at the drawn length (30 mm, the middle of 24..36) is the nominal mechanism.
    peaks = dict(re.findall(r"crank\s+([\d.]+) mm: peak drive (\S+)", p.stdout))
    nominal = cli_json("cycle", CRANK_ROCKER, "--json", "--steps", "36")["peaks"]["drive"]["peak"]
    assert float(peaks["30.00"]) == pytest.approx(nominal, rel=1e-5)  # printed to 6 digits


def test_docstrings_list_the_commands_options():
    assert "--t-end" in orthomech.simulate.__doc__
    assert "--steps" in orthomech.cycle.__doc__
    assert "forward dynamics" in orthomech.simulate.__doc__


def test_keyword_options():
    # from_ (a Python keyword) is --from; a negative number stays one argument.
    doc = cli_json("cycle", CRANK_ROCKER, "--json", "--from", "-30", "--to", "30", "--steps", "12")
    r = orthomech.cycle(CRANK_ROCKER, from_=-30, to=30, steps=12)
    assert orthomech.to_json(r) == doc
