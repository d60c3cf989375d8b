"""Errors reach Python as exceptions with locations; nothing a user passes crashes."""
import math

import numpy as np
import pytest

import kanesim

PENDULUM = """model P
  World world;
  Revolute hinge(axis = {0, 0, 1});
  Rod rod(L = 1, m = 1);
equation
  connect(world.frame_b, hinge.frame_a);
  connect(hinge.frame_b, rod.frame_a);
end P;
"""


def test_language_error_has_code_and_location():
    with pytest.raises(kanesim.ModelError) as e:
        kanesim.loads(PENDULUM.replace("axis =", "axs ="), name="typo.mech")
    err = e.value
    assert (err.code, err.file, err.line, err.column) == ("E203", "typo.mech", 3, 18)
    text = str(err)
    assert text.startswith("typo.mech:3:18: error[E203]")
    assert "^~~" in text and "did you mean 'axis'" in text


def test_compile_error_has_code_and_location():
    bad = PENDULUM.replace("Rod rod(L = 1, m = 1);",
                           "Body rod(m = 1, I = {{1, 0, 0}, {0, 1, 0}, {0, 0, 3}});")
    with pytest.raises(kanesim.ModelError) as e:
        kanesim.loads(bad, name="inertia.mech")
    assert e.value.code == "K308"
    assert e.value.file == "inertia.mech" and e.value.line == 4
    assert "triangle" in str(e.value)


def test_missing_file_and_unknown_parameter(examples):
    with pytest.raises(kanesim.ModelError) as e:
        kanesim.load(examples / "no_such_model.mech")
    assert "no_such_model.mech" in str(e.value)
    with pytest.raises(kanesim.ModelError) as e:
        kanesim.load(examples / "spring_mass.mech", set={"kk": 3})
    assert e.value.code.startswith("E") and "kk" in str(e.value)


def test_bad_run_settings_are_value_errors(examples):
    m = kanesim.load(examples / "spring_mass.mech")
    with pytest.raises(ValueError, match="rtol"):
        m.run(rtol=-1)
    with pytest.raises(ValueError, match="interval"):
        m.run(interval=float("nan"))
    with pytest.raises(ValueError, match="slider.q"):
        m.run(outputs=["slider.qq"])  # "did you mean"
    with pytest.raises(ValueError):
        m.run(stop_time=1e9, interval=1e-3)  # too many rows
    with pytest.raises(ValueError, match="integrator"):
        m.run(integrator="euler")
    with pytest.raises(TypeError):
        m.run(stop_time="soon")
    with pytest.raises(TypeError):
        kanesim.load(examples / "spring_mass.mech", set={"k": object()})
    with pytest.raises(kanesim.ModelError):
        kanesim.load(examples / "spring_mass.mech", set={"k": math.inf})


def test_numerical_failure_keeps_the_rows(source_dir):
    m = kanesim.load(source_dir / "tests" / "sim" / "data" / "nan_torque.mech")
    with pytest.raises(kanesim.SimulationError) as e:
        m.run()
    err = e.value
    assert 0.5 <= err.time <= 0.6 and "NaN" in err.cause
    r = err.result
    assert 5 <= len(r) <= 6 and np.all(r.time < err.time + 1e-12)
    assert np.all(np.isfinite(r.values))


def test_names_and_choices_are_checked(examples):
    path = examples / "spring_mass.mech"
    with pytest.raises(ValueError, match="solver"):
        kanesim.load(path, solver="bogus")
    with pytest.raises(ValueError, match="not a parameter name"):
        kanesim.load(path, set={"k=1": 2})
    with pytest.raises(ValueError, match="NaN"):
        kanesim.sweep(kanesim.load(path), grid={"k": [float("nan"), 1.0]})
    with pytest.raises(kanesim.ModelError) as e:
        kanesim.loads("model M\0 end M;")
    assert e.value.code == "L001" and e.value.line == 1
    with pytest.raises(kanesim.ModelError, match="directory"):
        kanesim.load(examples)
