"""kanesim from Python: load a .mech model, check it, run it into NumPy arrays, sweep it,
linearize it.

    import kanesim
    m = kanesim.load("examples/double_pendulum.mech", set={"shoulder_damping": 0.1})
    r = m.run(stop_time=2, outputs=["*.q"])
    r.time, r["shoulder.q"]

See docs/python.md. The compiled core is kanesim._kanesim; this file is the Python face.
"""

from __future__ import annotations

import csv
import math
import numbers
import os
import threading
import warnings as _warnings
from collections import OrderedDict
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Union

import numpy as np

from . import _kanesim


def _check_array_layout() -> None:
    """Refuses to import when the compiled module's arrays would not read back as written.

    pybind11 before 2.12 reads NumPy's dtype struct with NumPy 1's layout; under NumPy 2 a
    new array then gets stride 0 and every element reads as the first (Result.time all
    zeros), silently. The module says which pybind11 built it, and makes known arrays the
    way it makes every result (python/src/module.cpp, LayoutProbe): both are checked here."""
    built = tuple(getattr(_kanesim, "_pybind11_version", (0, 0, 0)))
    numpy_major = int(np.__version__.split(".")[0])
    fix = ("reinstall it with `python3 -m pip install .` (pyproject.toml builds it with pybind11 >= 2.12 from "
           "PyPI; docs/python.md), or use NumPy 1.x")
    if numpy_major >= 2 and built[:2] < (2, 12):
        raise ImportError(f"kanesim: this module was built with pybind11 {'.'.join(map(str, built))}, which predates "
                          f"NumPy 2: with NumPy {np.__version__} its arrays would hold wrong numbers; {fix}")
    vector, rows, matrix, complexes = _kanesim._layout_probe()
    want = np.arange(1.0, 7.0).reshape(2, 3)
    good = (vector.tolist() == [1.0, 2.0, 3.0] and rows.tolist() == want.tolist() and matrix.tolist() == want.tolist()
            and complexes.tolist() == [1 + 2j, 3 - 4j]
            and all(a.flags.c_contiguous and a.flags.owndata for a in (vector, rows, matrix, complexes)))
    if not good:
        raise ImportError(f"kanesim: the compiled module's arrays do not read back under NumPy {np.__version__} "
                          f"(pybind11 {'.'.join(map(str, built))}; strides {vector.strides}, {rows.strides}): "
                          f"the results would be wrong numbers; {fix}")


_check_array_layout()

__all__ = ["load", "loads", "sweep", "Model", "Result", "LinearModel", "Table", "Simulator", "ModelError", "SimulationError", "KanesimWarning"]
__version__ = "0.1.0"

_NAN = float("nan")


class ModelError(Exception):
    """A model error: the message is the rendered diagnostic (file:line:col, the source
    line with a caret, notes, hint), as `kanesim check` prints it.

    .code    the diagnostic code ("E203", "K308"; "" when there is none)
    .file    the file of the first error ("" when it has no location)
    .line, .column   1-based place of the first error (0 when none)
    """

    def __init__(self, message: str, code: str = "", file: str = "", line: int = 0, column: int = 0):
        super().__init__(message)
        self.code = code
        self.file = file
        self.line = line
        self.column = column


class SimulationError(RuntimeError):
    """A numerical failure (the command line's exit 2): the run stopped at .time because of
    .cause; .result holds the rows computed before it (None from Model.linearize)."""

    def __init__(self, message: str, time: float, cause: str, result: "Result"):
        super().__init__(message)
        self.time = time
        self.cause = cause
        self.result = result


class KanesimWarning(UserWarning):
    """A warning from the model or the run (a diagnostic warning, W313, a suspicious rtol)."""


def _value_text(value: Any) -> str:
    """A Python value as the text of `--set name=VALUE`."""
    if isinstance(value, str):
        return value  # an expression, as on the command line ('2*pi', '"text"' for a String)
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        return repr(float(value))  # shortest text that reads back as the same double
    if isinstance(value, (list, tuple, np.ndarray)):
        return "{" + ", ".join(_value_text(v) for v in value) + "}"
    raise TypeError(f"set: cannot pass a {type(value).__name__} as a parameter value")


def _set_list(values: Optional[Mapping[str, Any]]) -> List[str]:
    if values is None:
        return []
    if not isinstance(values, Mapping):
        raise TypeError("set= takes a dict of parameter name -> value")
    out = []
    for name, v in values.items():
        if not isinstance(name, str) or not name or "=" in name:
            raise ValueError(f"set: {name!r} is not a parameter name")
        out.append(f"{name}={_value_text(v)}")
    return out


def _choice(value: str, name: str, allowed: Sequence[str]) -> str:
    if value not in allowed:
        raise ValueError(f"{name}={value!r}: unknown ({', '.join(allowed)})")
    return value


_SOLVERS = ("auto", "dense", "sparse", "recursive")
_INTEGRATORS = ("auto", "ida", "cvode", "cvode-bdf", "arkode", "dop853")
_REACTIONS = ("nan", "min-norm")


def _time(x: Optional[float], name: str) -> float:
    if x is None:
        return _NAN
    try:
        value = float(x)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a number, got {x!r}") from None
    if math.isnan(value):  # NaN means "not given" below; a NaN given is refused here
        raise ValueError(f"{name} must be a number, got nan")
    return value


def _warn(messages: Iterable[str]) -> None:
    for w in messages:
        _warnings.warn(w.rstrip("\n"), KanesimWarning, stacklevel=3)


class Result:
    """The rows of a run: .time (1-D), .values (rows x columns), .columns (signal names),
    r["name"] (one column, 1-D), .stats (integrator statistics), .events (end stops and when
    clauses: dicts with time, element, kind and changes {name: (before, after)}; an event's
    two rows, its left and right limits, share its time), .terminated ((time, message) when a
    when clause's terminate ended the run, else None)."""

    def __init__(self, columns: List[str], time: np.ndarray, values: np.ndarray, stats: Dict[str, Any]):
        self.columns = list(columns)
        self.time = time
        self.values = values
        self.events = stats.pop("events", [])
        self.terminated = stats.pop("terminated", None)
        self.stats = stats
        self._index = {c: i for i, c in enumerate(self.columns)}

    def __getitem__(self, name: str) -> np.ndarray:
        if name == "time":
            return self.time
        try:
            return self.values[:, self._index[name]]
        except KeyError:
            raise KeyError(f"no column {name!r} in this result (columns: {', '.join(self.columns)})") from None

    def __contains__(self, name: str) -> bool:
        return name == "time" or name in self._index

    def __len__(self) -> int:
        return len(self.time)

    def keys(self) -> List[str]:
        return ["time"] + self.columns

    def sensitivity(self, signal: str, param: str) -> np.ndarray:
        """d(signal)/d(param) at every row, from a run with sensitivity=[..., param, ...]."""
        return self[f"d({signal})/d({param})"]

    def to_pandas(self):
        """A pandas DataFrame with a `time` column first (needs pandas)."""
        import pandas as pd

        data = {"time": self.time}
        for i, c in enumerate(self.columns):
            data[c] = self.values[:, i]
        return pd.DataFrame(data)

    def __repr__(self) -> str:
        return f"<kanesim.Result {len(self)} rows x {len(self.columns)} columns>"


class LinearModel:
    """A linear state-space model x' = A x + B w, y = C x + D w about an operating point
    (as `kanesim linearize`; docs/linearize.md).

    .A, .B, .C, .D     NumPy arrays (n x n, n x m, p x n, p x m)
    .states            state names: the independent coordinates, then the speeds
    .n_coordinates     how many of the states are coordinates
    .inputs, .outputs  the names of w and y
    .eigenvalues       complex NumPy array, sorted by modulus (then imaginary part descending)
    .modes             one dict per eigenvalue: eigenvalue, natural_frequency, frequency_hz,
                       damping_ratio, dominant [(state, weight)], shape (complex array)
    .ignorable         coordinates no other state reads (each gives a zero eigenvalue)
    .held              the rows held at the operating point, e.g. "j1 on q_min", "j1 stuck",
                       "floor on the plane" (their coordinate and speed are not states)
    .accuracy          {"step", "A", "BCD", "unsteady", "widened"}: the achieved accuracy of A
                       and of B, C, D, how much A changes along the motion (0 at an
                       equilibrium), and {column: step used} for the columns whose step was
                       below the rounding floor and was widened (docs/linearize.md "Accuracy")
    .time              the time of the operating point
    .equilibrium       with equilibrium=True: {"iterations", "relaxation_steps", "residual",
                       "moved": [(coordinate, change)]}; else None
    """

    def __init__(self, data: Dict[str, Any]):
        self.A = data["A"]
        self.B = data["B"]
        self.C = data["C"]
        self.D = data["D"]
        self.states: List[str] = list(data["states"])
        self.n_coordinates: int = data["n_coordinates"]
        self.inputs: List[str] = list(data["inputs"])
        self.outputs: List[str] = list(data["outputs"])
        self.eigenvalues: np.ndarray = data["eigenvalues"]
        self.modes: List[Dict[str, Any]] = list(data["modes"])
        self.ignorable: List[str] = list(data["ignorable"])
        self.held: List[str] = list(data["held"])
        self.accuracy: Dict[str, Any] = dict(data["accuracy"])
        self.time: float = data["time"]
        self.equilibrium: Optional[Dict[str, Any]] = data["equilibrium"]
        self.seconds: float = data["seconds"]

    @property
    def stable(self) -> bool:
        """True when every eigenvalue has a negative real part (asymptotically stable)."""
        return bool(len(self.eigenvalues) > 0 and np.all(self.eigenvalues.real < 0))

    def __repr__(self) -> str:
        return (f"<kanesim.LinearModel {len(self.states)} states, {len(self.inputs)} inputs, "
                f"{len(self.outputs)} outputs at t = {self.time!r}>")


class Model:
    """A loaded and compiled model. Immutable: run() may be called from several threads at
    once (each run has its own workspace; the GIL is released while it integrates)."""

    _MAX_VARIANTS = 16

    def __init__(self, compiled, load_args: Dict[str, Any], sets: Dict[str, Any]):
        self._compiled = compiled
        self._load_args = load_args
        self._sets = dict(sets)
        self._variants: "OrderedDict[tuple, Model]" = OrderedDict()
        self._lock = threading.Lock()

    @property
    def path(self) -> str:
        return self._compiled.path

    @property
    def warnings(self) -> List[str]:
        """The diagnostics' warnings, rendered."""
        return list(self._compiled.warnings)

    @property
    def signals(self) -> List[str]:
        """Every signal run(outputs=...) can select (dotted names)."""
        return self._compiled.signals()

    def check(self) -> Dict[str, Any]:
        """The summary of `kanesim check`: bodies, joints, DOF, solver, integrator (with the
        reasons), the experiment, the model's parameters and outputs."""
        return self._compiled.check()

    def with_set(self, values: Mapping[str, Any]) -> "Model":
        """This model with more parameter values set (loaded and compiled again; cached)."""
        merged = dict(self._sets)
        merged.update(values)
        key = tuple(_set_list(merged))
        with self._lock:
            hit = self._variants.get(key)
            if hit is not None:
                self._variants.move_to_end(key)
                return hit
        variant = _load(dict(self._load_args), merged)
        with self._lock:
            self._variants[key] = variant
            while len(self._variants) > self._MAX_VARIANTS:
                self._variants.popitem(last=False)
        return variant

    def run(
        self,
        stop_time: Optional[float] = None,
        rtol: Optional[float] = None,
        atol: Optional[float] = None,
        interval: Optional[float] = None,
        outputs: Optional[Sequence[str]] = None,
        set: Optional[Mapping[str, Any]] = None,
        start_time: Optional[float] = None,
        integrator: str = "auto",
        linear_solver: str = "auto",
        projection: str = "eval",
        energy_check: str = "on",
        sensitivity: Optional[Sequence[str]] = None,
    ) -> Result:
        """Simulates, like `kanesim run`: None takes the model's experiment annotation
        (atol defaults to rtol); outputs are the --output globs; sensitivity: Real parameters
        p whose derivatives d(y)/d(p) ride along (Result.sensitivity(y, p), like
        `--sensitivity`). Raises SimulationError (with the rows so far) on a numerical
        failure, ValueError on bad settings."""
        if set:
            return self.with_set(set).run(stop_time, rtol, atol, interval, outputs, None, start_time, integrator,
                                          linear_solver, projection, energy_check, sensitivity)
        if isinstance(outputs, str):
            outputs = [outputs]
        if isinstance(sensitivity, str):
            sensitivity = [sensitivity]
        columns, time, values, stats, failure, warns = _kanesim.run(
            self._compiled, _time(start_time, "start_time"), _time(stop_time, "stop_time"),
            _time(interval, "interval"), _time(rtol, "rtol"), _time(atol, "atol"), list(outputs or []),
            integrator, linear_solver, projection, energy_check, list(sensitivity or []))
        _warn(warns)
        result = Result(columns, time, values, stats)
        if failure is not None:
            t, cause = failure
            raise SimulationError(f"numerical failure at t = {t!r}: {cause}", t, cause, result)
        return result

    def simulator(
        self,
        rtol: Optional[float] = None,
        atol: Optional[float] = None,
        integrator: str = "auto",
        outputs: Optional[Sequence[str]] = None,
        start_time: Optional[float] = None,
    ) -> "Simulator":
        """A simulator that the caller steps (a controller in Python): the model's inputs set
        between steps, one integration carried across them (docs/python.md "Stepping")."""
        if isinstance(outputs, str):
            outputs = [outputs]
        core = _kanesim.simulator(self._compiled, _time(start_time, "start_time"), _time(rtol, "rtol"),
                                  _time(atol, "atol"), list(outputs or []), integrator)
        return Simulator(core)

    def linearize(
        self,
        at: Optional[float] = None,
        equilibrium: bool = False,
        inputs: Optional[Union[Sequence[str], Mapping[str, Optional[float]]]] = None,
        outputs: Optional[Sequence[str]] = None,
        set: Optional[Mapping[str, Any]] = None,
        step: float = 1e-3,
        frozen: bool = False,
    ) -> LinearModel:
        """The linear model about an operating point, like `kanesim linearize`: the start
        values, the motion at time `at`, or (equilibrium=True) a static equilibrium found
        from either. inputs: "JOINT.tau", "JOINT.tau[k]" or real parameters, columns of B
        and D; as a mapping it also gives the model's own inputs (`input Real u;`) their
        values at the operating point, {"u": 0.5} (each is then a column too, as `kanesim
        linearize --set u=0.5`), the other names mapped to None; outputs: signal names. Raises ModelError for bad input (an unknown input or output, an
        operating point off the constraints), SimulationError for a numerical failure
        (singular configuration, no equilibrium, or an operating point that is neither an
        equilibrium nor a steady motion in these coordinates), ValueError for a bad step or
        time. frozen=True accepts the eigenvalues of such a frozen instant with a
        KanesimWarning, like `kanesim linearize --frozen`."""
        if set:
            return self.with_set(set).linearize(at, equilibrium, inputs, outputs, None, step, frozen)
        if isinstance(inputs, str):
            inputs = [inputs]
        if isinstance(outputs, str):
            outputs = [outputs]
        values = []  # the model's inputs' values (name, value)
        if isinstance(inputs, Mapping):
            values = [(str(k), float(v)) for k, v in inputs.items() if v is not None]
            inputs = [str(k) for k, v in inputs.items() if v is None]
        at_value = _time(at, "at")
        data = _kanesim.linearize(self._compiled, at is not None, 0.0 if at is None else at_value, bool(equilibrium),
                                  [str(x) for x in inputs or []], [str(x) for x in outputs or []],
                                  float(step), values)
        failure = data["failure"]
        if failure is not None:
            code, message, hint, file, line, column = failure
            text = f"kanesim linearize: {'error' if code == 1 else 'numerical failure'}: {message}"
            if line > 0:
                text += f"\n{file}:{line}:{column}: note: declared here"
            if hint:
                text += f"\n  hint: {hint}"
            if code == 1:
                raise ModelError(text, "", file if line > 0 else "", line, column)
            raise SimulationError(text, data["time"], message, None)
        model = LinearModel(data)
        unsteady = model.accuracy["unsteady"]
        if unsteady > 1e-6:
            cause = (f"the operating point is neither an equilibrium nor a steady motion in these coordinates "
                     f"(A changes by {unsteady:.1e} relative along the motion): the eigenvalues would be those "
                     f"of a frozen instant, not stability exponents")
            if not frozen:
                raise SimulationError(
                    f"kanesim linearize: numerical failure at t = {data['time']!r}: {cause}\n  hint: use "
                    f"equilibrium=True, or joints whose coordinates follow the motion's symmetry (docs/linearize.md, "
                    f"\"Steady motions\"); frozen=True accepts the eigenvalues of the frozen instant",
                    data["time"], cause, None)
            _warn([f"(frozen=True) {cause}"])
        return model

    def __repr__(self) -> str:
        return f"<kanesim.Model {self.path!r}>"


class Simulator:
    """The model stepped by its caller (Model.simulator()). step(dt, inputs={...}) and
    advance_to(t, inputs={...}) set the inputs, then integrate (the GIL released);
    .outputs (NumPy, in .output_names order) and sim[name] read the signals at .time;
    get_state() / set_state(s) continue bit for bit; reset() goes back to the start. The
    run's events happen inside the steps (.events, as Result.events); a terminate(...) ends
    the step at its event (.terminated == (time, message)). A numerical failure raises
    SimulationError (.result is None); the simulator then refuses to step until reset() or
    set_state(), as after a terminate."""

    def __init__(self, core):
        self._core = core

    def step(self, dt: float, inputs: Optional[Mapping[str, float]] = None) -> None:
        try:
            self._core.step(dt, inputs)
        except _kanesim._StepFailed as e:
            raise _step_error(e) from None

    def advance_to(self, t: float, inputs: Optional[Mapping[str, float]] = None) -> None:
        try:
            self._core.advance_to(t, inputs)
        except _kanesim._StepFailed as e:
            raise _step_error(e) from None

    def set_inputs(self, inputs: Mapping[str, float]) -> None:
        self._core.set_inputs(inputs)

    @property
    def time(self) -> float:
        return self._core.time

    @property
    def outputs(self) -> np.ndarray:
        return self._core.outputs

    @property
    def output_names(self) -> List[str]:
        return self._core.output_names

    @property
    def inputs(self) -> Dict[str, float]:
        return self._core.inputs

    @property
    def input_names(self) -> List[str]:
        return self._core.input_names

    @property
    def state(self) -> np.ndarray:
        """The integrator's state y = [q, u] (free coordinates and speeds) at .time."""
        return self._core.state

    @property
    def method(self) -> str:
        return self._core.method

    @property
    def events(self) -> List[Dict[str, Any]]:
        """The events since the start, as Result.events (set_state keeps those up to its time)."""
        return self._core.events

    @property
    def terminated(self):
        """(time, message) once a terminate(...) fired, else None."""
        return self._core.terminated

    def stats(self) -> Dict[str, Any]:
        return self._core.stats()

    def __getitem__(self, name: str) -> float:
        return self._core.get(name)

    def get_state(self):
        """The state at .time (a tuple of plain values: it pickles); restarts the solver there,
        as set_state does, so that both continue alike."""
        return self._core.get_state()

    def set_state(self, state) -> None:
        self._core.set_state(state)

    def reset(self) -> None:
        self._core.reset()

    def __repr__(self) -> str:
        return f"<kanesim.Simulator t={self.time!r} {self.method} inputs={self.input_names}>"


def _step_error(e) -> SimulationError:
    t, cause = e.args
    if cause.startswith("the model terminated"):  # a step after terminate(...): no failure
        return SimulationError(cause, t, cause, None)
    return SimulationError(f"numerical failure at t = {t!r}: {cause}", t, cause, None)


def _load(args: Dict[str, Any], sets: Dict[str, Any]) -> Model:
    compiled, error = _kanesim.load(args["path"], args["text"], args["from_text"], args["model"] or "",
                                    _set_list(sets), args["solver"], args["integrator"], args["reactions"],
                                    args.get("floating", False), list(args.get("package_path", ())),
                                    args.get("limits", "stops") == "stops")
    if compiled is None:
        code, file, line, column, rendered = error
        raise ModelError(rendered.rstrip("\n"), code, file, line, column)
    _warn(compiled.warnings)
    return Model(compiled, args, sets)


def _with_starts(set, start) -> dict:
    """set= plus start= ({"j.q": 0.3} is --set j.q.start=0.3): one dict of --set values."""
    out = dict(set or {})
    if start is None:
        return out
    if not isinstance(start, Mapping):
        raise TypeError("start= takes a dict of variable name -> start value")
    for name, v in start.items():
        if not isinstance(name, str) or not name or "=" in name:
            raise ValueError(f"start: {name!r} is not a variable name")
        out[name + ".start"] = v
    return out


def load(path, set: Optional[Mapping[str, Any]] = None, model: Optional[str] = None, solver: str = "auto",
         integrator: str = "auto", reactions: str = "nan", floating: bool = False,
         package_path: Sequence[str] = (), start: Optional[Mapping[str, Any]] = None,
         limits: str = "stops") -> Model:
    """Loads, elaborates and compiles a .mech file, or a URDF robot (robot.urdf, translated as
    `kanesim import` does: docs/import.md; floating, limits ("stops" or "ignore") and
    package_path as its --floating, --limits and --package-path). set: parameter values as --set takes
    them ({"N": 20, "world.g": [0, 0, -9.81], "flag": True, "j.q.start": 0.3}); start:
    start values of joint coordinates and speeds ({"j.q": 0.3, "free.u": [...]}, the same
    as set={"j.q.start": 0.3}); model: the model to elaborate (default: the last in the
    file). Raises ModelError."""
    if isinstance(package_path, (str, os.PathLike)):
        package_path = [package_path]
    args = dict(path=os.fspath(path), text="", from_text=False, model=model,
                solver=_choice(solver, "solver", _SOLVERS), integrator=_choice(integrator, "integrator", _INTEGRATORS),
                reactions=_choice(reactions, "reactions", _REACTIONS), floating=bool(floating),
                limits=_choice(limits, "limits", ("stops", "ignore")),
                package_path=[os.fspath(p) for p in package_path])
    return _load(args, _with_starts(set, start))


def loads(text: str, set: Optional[Mapping[str, Any]] = None, model: Optional[str] = None,
          name: str = "<string>.mech", solver: str = "auto", integrator: str = "auto",
          reactions: str = "nan", start: Optional[Mapping[str, Any]] = None) -> Model:
    """Like load(), from the model's text; diagnostics name it `name`."""
    if not isinstance(text, str):
        raise TypeError("loads() takes the model's text as a str")
    args = dict(path=name, text=text, from_text=True, model=model,
                solver=_choice(solver, "solver", _SOLVERS), integrator=_choice(integrator, "integrator", _INTEGRATORS),
                reactions=_choice(reactions, "reactions", _REACTIONS))
    return _load(args, _with_starts(set, start))


class Table:
    """A sweep's summary: the columns of `kanesim sweep`'s summary.csv (id, the parameters,
    stop_time, rtol, atol, status, message, fail_time, the metrics, integrator statistics,
    wall_time), numbers as NumPy arrays, text as lists."""

    _TEXT = {"status", "message", "method"}

    def __init__(self, header: str, lines: List[str], failed: int):
        names = next(csv.reader([header]))
        rows = list(csv.reader(lines))
        self.columns: List[str] = names
        self.failed = failed
        self._data: Dict[str, Any] = {}
        for j, name in enumerate(names):
            cells = [r[j] for r in rows]
            if name in self._TEXT:
                self._data[name] = cells
            elif name == "id":
                self._data[name] = np.array([int(c) for c in cells], dtype=np.int64)
            else:
                self._data[name] = np.array([float(c) if c != "" else math.nan for c in cells], dtype=float)

    def __getitem__(self, name: str):
        return self._data[name]

    def __len__(self) -> int:
        return len(self._data["id"]) if "id" in self._data else 0

    def to_pandas(self):
        """A pandas DataFrame, one row per scenario (needs pandas)."""
        import pandas as pd

        return pd.DataFrame({c: self._data[c] for c in self.columns})

    def __repr__(self) -> str:
        return f"<kanesim.Table {len(self)} scenarios, {self.failed} failed>"


def _columns(arg, what: str):
    if arg is None:
        return []
    if not isinstance(arg, Mapping):
        raise TypeError(f"{what}= takes a dict of parameter name -> values")
    out = []
    for name, values in arg.items():
        if isinstance(values, (str, bytes)) or not isinstance(values, Iterable):
            values = [values]
        values = [float(v) for v in values]
        if any(math.isnan(v) for v in values):
            raise ValueError(f"{what}: {name!r} has a NaN (leave a parameter out to keep the model's value)")
        out.append((str(name), values))
    return out


def sweep(model: Model, grid: Optional[Mapping[str, Sequence[float]]] = None,
          samples: Optional[Mapping[str, Sequence[float]]] = None, metrics: Sequence[str] = (), threads: int = 0,
          stop_time: Optional[float] = None, rtol: Optional[float] = None, atol: Optional[float] = None,
          interval: Optional[float] = None, start_time: Optional[float] = None, integrator: str = "auto",
          energy_check: str = "on", isolation: str = "process", scenario_timeout: float = 0) -> Table:
    """Runs many scenarios of one model in parallel, like `kanesim sweep`:
    grid={"k": [10, 20], "m": [1, 2]} is the Cartesian product (first key slowest);
    samples={"k": [...], "m": [...]} are rows taken together (equal lengths); both combine
    as a product. metrics as --metric ("final:S", "min:S", "max:S", "mean:S", "rms:S",
    "cross:S=L"). threads=0: all cores. energy_check as run()'s ("on", "off", "report"):
    with "on" a scenario whose energy leaves the tolerance's reach fails.
    isolation="process" (default): scenarios run in worker processes forked from this one,
    so a scenario that crashes costs its own row (status "crashed"), never the interpreter;
    scenario_timeout=S (seconds, 0: none) stops one that runs longer (status "timeout").
    isolation="thread": on threads of this process (a crash ends the interpreter).
    Returns a Table; rows whose status is not "ok" are counted in Table.failed."""
    if isinstance(metrics, str):
        metrics = [metrics]
    header, lines, failed, warning = _kanesim.sweep(
        model._compiled, _columns(grid, "grid"), _columns(samples, "samples"), list(metrics), int(threads),
        _time(start_time, "start_time"), _time(stop_time, "stop_time"), _time(interval, "interval"),
        _time(rtol, "rtol"), _time(atol, "atol"), integrator, energy_check, str(isolation), float(scenario_timeout))
    if warning:
        _warnings.warn(warning, RuntimeWarning, stacklevel=2)
    return Table(header, lines, failed)
