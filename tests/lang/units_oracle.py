#!/usr/bin/env python3
"""`kanesim units` against pint, an independent unit library (PyPI; the test venv only).

Each case is built twice from one description: as a Modelica unit string for kanesim
("kN.m2/(ms.rad)") and as a pint expression of full unit names ("(kilonewton)**1 * ..."),
so pint reads its own names, never kanesim's symbols. The seven SI dimension exponents and
the scale to the coherent SI unit must agree (pint counts the radian as dimensionless, as
the check does). Malformed strings must be refused.
Usage: units_oracle.py KANESIM   (exit 0 when every case agrees)
"""
import math
import random
import subprocess
import sys

import pint

SYMBOLS = {  # Modelica symbol -> pint name
    "m": "meter", "g": "gram", "s": "second", "A": "ampere", "K": "kelvin", "mol": "mole",
    "cd": "candela", "rad": "radian", "sr": "steradian", "deg": "degree", "rev": "revolution",
    "Hz": "hertz", "N": "newton", "Pa": "pascal", "J": "joule", "W": "watt", "C": "coulomb",
    "V": "volt", "F": "farad", "Ohm": "ohm", "S": "siemens", "Wb": "weber", "T": "tesla",
    "H": "henry", "lm": "lumen", "lx": "lux", "Bq": "becquerel", "Gy": "gray", "Sv": "sievert",
    "kat": "katal", "min": "minute", "h": "hour", "d": "day", "l": "liter", "L": "liter",
    "bar": "bar", "t": "metric_ton",
}
PREFIXES = {
    "": "", "Y": "yotta", "Z": "zetta", "E": "exa", "P": "peta", "T": "tera", "G": "giga",
    "M": "mega", "k": "kilo", "h": "hecto", "da": "deca", "d": "deci", "c": "centi", "m": "milli",
    "u": "micro", "\u00b5": "micro", "n": "nano", "p": "pico", "f": "femto", "a": "atto",
}
# What Modelica models write, by hand.
FIXED = [
    ("N.m/rad", "newton*meter/radian"), ("kg.m2", "kilogram*meter**2"), ("m/s2", "meter/second**2"),
    ("1", "dimensionless"), ("1/s", "1/second"), ("N.m.s/rad", "newton*meter*second/radian"),
    ("kg/m3", "kilogram/meter**3"), ("rad/s", "radian/second"), ("W/(m2.K)", "watt/(meter**2*kelvin)"),
    ("J/(kg.K)", "joule/(kilogram*kelvin)"), ("m3/s", "meter**3/second"), ("kN/mm", "kilonewton/millimeter"),
    ("deg/s", "degree/second"), ("rev/min", "revolution/minute"), ("um", "micrometer"),
    ("\u00b5m", "micrometer"), ("N/mm", "newton/millimeter"), ("s-1", "1/second"), ("m.s-2", "meter/second**2"),
    ("mm2", "millimeter**2"), ("kg.m/s2", "kilogram*meter/second**2"), ("(N.m)/(rad/s)", "newton*meter/(radian/second)"),
    ("Pa.s", "pascal*second"), ("kW.h", "kilowatt*hour"), ("mA.h", "milliampere*hour"), ("g/cm3", "gram/centimeter**3"),
    ("MPa", "megapascal"), ("GPa", "gigapascal"), ("dam", "decameter"), ("ns", "nanosecond"),
]
BAD = ["", "N..m", "m/", "/s", "2m", "xyz", "m^2", "kg.", "(m", "m)", "m/(s", "N.m/rad/", "1.m", "m+", "mm-"]


def factor(rng):
    while True:
        sym = rng.choice(list(SYMBOLS))
        pre = rng.choice(list(PREFIXES)) if rng.random() < 0.5 else ""
        word = pre + sym
        if pre and word in SYMBOLS:
            continue  # "cd" is the candela, not a centi-day: Modelica reads the symbol first
        if pre and any(word == p + s for p in PREFIXES if p and p != pre for s in SYMBOLS):
            continue  # two readings of one word
        break
    e = rng.choice([1, 1, 1, 2, 3, -1, -2])
    text = word + ("" if e == 1 else str(e))
    return text, f"({PREFIXES[pre]}{SYMBOLS[sym]})**{e}"


def generated(n, seed=43):
    rng = random.Random(seed)
    cases = []
    for _ in range(n):
        num = [factor(rng) for _ in range(rng.randint(1, 3))]
        text = ".".join(t for t, _ in num)
        expr = "*".join(p for _, p in num)
        r = rng.random()
        if r < 0.35:
            t, p = factor(rng)
            text, expr = f"{text}/{t}", f"({expr})/{p}"
        elif r < 0.6:
            den = [factor(rng) for _ in range(2)]
            text += "/(" + ".".join(t for t, _ in den) + ")"
            expr = f"({expr})/(" + "*".join(p for _, p in den) + ")"
        cases.append((text, expr))
    return cases


DIMS = ["[length]", "[mass]", "[time]", "[current]", "[temperature]", "[substance]", "[luminosity]"]


def main():
    kanesim = sys.argv[1]
    ureg = pint.UnitRegistry()
    cases = FIXED + generated(400)
    out = subprocess.run([kanesim, "units", *[t for t, _ in cases]], capture_output=True, text=True)
    lines = out.stdout.splitlines()
    assert len(lines) == len(cases), (len(lines), len(cases), out.stderr)
    bad = 0
    for (text, expr), line in zip(cases, lines):
        q = ureg.Quantity(1, expr).to_base_units()
        want_exp = [float(q.dimensionality.get(d, 0)) for d in DIMS]
        want_scale = float(q.magnitude)
        try:
            head, exps = line.rsplit("[", 1)
            got_exp = [float(x) for x in exps.rstrip("]").split()][:7]
            got_scale = float(head.split(" = ", 1)[1].split(" * ")[0])
        except (ValueError, IndexError):
            print(f"FAIL {text!r}: {line}")
            bad += 1
            continue
        if got_exp != want_exp or not math.isclose(got_scale, want_scale, rel_tol=1e-12):
            print(f"FAIL {text!r}: kanesim {got_scale} {got_exp}, pint {want_scale} {want_exp}")
            bad += 1
    for text in BAD:
        r = subprocess.run([kanesim, "units", text], capture_output=True, text=True)
        if r.returncode != 1 or "not a unit" not in r.stdout:
            print(f"FAIL {text!r} accepted: {r.stdout}")
            bad += 1
    print(f"{len(cases)} unit strings against pint, {len(BAD)} malformed: {bad} disagree")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
