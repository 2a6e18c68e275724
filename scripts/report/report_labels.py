"""The report's one labeller: how a parameter's value is named in every legend, tick, title and table
of the report (docs/report.md, "Labels").

A value is named in the study's words, from the parameter's entry in the column manifest (its unit,
its kind, its levels, and what its description says of its sign), never as the float it is stored as:

    value_label("wind_20ft_mps", -15.433333)   # "W20 = 30 kt headwind"
    value_label("h_derivatives", 1)            # "with h-derivatives"
    value_label("speed_mps", 32.0208)          # "u0 = 32.02 m/s"
    value_label("cdh", 1, ["polar", "zero"])   # "cdh = zero"

Numbers keep at most MAX_SIGNIFICANT significant digits (`number`). A mean wind whose description says
that a headwind is negative (docs/model.md §9: `wind_20ft_mps` is the wind's u_g) is shown in knots, with
its sign as the word headwind or tailwind.
"""

import math
import os
import sys

_LIB = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "lib")
if _LIB not in sys.path:
    sys.path.insert(0, _LIB)
import columns  # noqa: E402  (scripts/lib/columns.py: the manifest's design parameters)

# No label shows more significant digits than this: "32.02 m/s", not "32.0208 m/s"; the archive's
# exact value is in the tables and the provenance.
MAX_SIGNIFICANT = 4
# One knot in m/s (1852 m per hour, exactly).
KNOT_MPS = 1852.0 / 3600.0
# The words of a parameter's manifest description that make it a signed mean wind (docs/model.md §9).
HEADWIND_NEGATIVE = "a headwind is negative"
# The symbols of the parameters a reader of this field knows by their symbol; any other parameter is
# named by its key.
SYMBOLS = {
    "speed_mps": "u0", "height_m": "H", "wind_20ft_mps": "W20", "turbulence_sigma_w_mps": "σ_w",
    "pulse_amplitude_deg": "pulse", "pulse_duration_s": "pulse length", "glide_slope_deg": "γ",
    "flare_height_m": "Ho", "flare_time_constant_s": "τ", "mass_kg": "m", "pitch_inertia_kgm2": "Iy",
    "flare_tau_s": "τ",  # flare_time_constant_s in an archive written before its rename (docs/sweep.md)
    "gust_amplitude_mps": "v_m", "gust_half_length_m": "d_m", "cg_shift_over_chord": "CG shift / c",
}
# Booleans named as a clause ("with h-derivatives") rather than "name = true".
BOOLEAN_WORDS = {"h_derivatives": ("without h-derivatives", "with h-derivatives")}
# Units as a reader writes them after a number.
UNIT_TEXT = {"1": "", "deg": "°", "kg m^2": "kg m²", "rad^2": "rad²"}


def number(value, digits=MAX_SIGNIFICANT):
    """`value` with at most `digits` significant digits, in plain notation from 10⁻³ to 10⁵ (trailing
    zeros dropped: 15, 32.02, 0.0125), in scientific notation beyond ("2.5e-05")."""
    value = float(value)
    if not math.isfinite(value):
        return "—" if math.isnan(value) else ("∞" if value > 0 else "−∞")
    if value == 0:
        return "0"
    magnitude = abs(value)
    if not 1e-3 <= magnitude < 1e5:
        mantissa, exponent = f"{value:.{digits - 1}e}".split("e")
        return f"{mantissa.rstrip('0').rstrip('.')}e{int(exponent):+03d}"
    rounded = float(f"{value:.{digits}g}")  # the digits kept, then written out without an exponent
    decimals = max(0, digits - 1 - int(math.floor(math.log10(abs(rounded)))))
    text = f"{rounded:.{decimals}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def parameter(name):
    """The manifest entry of a design parameter (units, kind, levels, description), or None."""
    for entry in columns.manifest()["design"]:
        if entry["name"] == name:
            return entry
    return None


def symbol(name):
    """How the parameter is named in a label: its symbol, else its key."""
    return SYMBOLS.get(name, name)


def unit_text(units):
    return UNIT_TEXT.get(units, units)


def signed_wind(name):
    """Whether the parameter is a mean wind whose sign says headwind or tailwind (its description)."""
    entry = parameter(name)
    return bool(entry) and entry["units"] == "m/s" and HEADWIND_NEGATIVE in entry["description"]


def wind_words(value_mps):
    """A u_g in m/s as knots and a direction: "30 kt headwind", "5 kt tailwind", "calm"."""
    knots = abs(float(value_mps)) / KNOT_MPS
    if float(number(knots)) == 0:
        return "calm"
    return f"{number(knots)} kt {'headwind' if value_mps < 0 else 'tailwind'}"


def quantity(name, value):
    """The value of a real parameter with its unit, without its name: "30 kt headwind", "32.02 m/s"."""
    if signed_wind(name):
        return wind_words(value)
    entry = parameter(name)
    unit = unit_text(entry["units"]) if entry else ""
    if unit == "°":
        return f"{number(value)}°"
    return f"{number(value)} {unit}".rstrip()


def value_label(name, value, levels=None):
    """The label of one value of one parameter, in words (see the module's docstring). `levels`: the
    level names of a choice or boolean parameter, as the archive stores them (else the manifest's)."""
    entry = parameter(name)
    if levels is None:
        levels = list(entry["levels"]) if entry else []
    value = float(value)
    if levels and value.is_integer() and 0 <= int(value) < len(levels):
        level = levels[int(value)]
        if name in BOOLEAN_WORDS and level in ("false", "true"):
            return BOOLEAN_WORDS[name][level == "true"]
        return f"{symbol(name)} = {level}"
    return f"{symbol(name)} = {quantity(name, value)}"


def key_label(key, levels_of=None):
    """The label of a group of runs: its key {parameter: value}, each value labelled, joined by commas.
    `levels_of(name)` gives a parameter's level names as the archive stores them."""
    return ", ".join(value_label(name, value, levels_of(name) if levels_of else None) for name, value in key.items())


def axis_label(name):
    """An axis or column heading for a parameter: "W20 (kt, headwind or tailwind)", "u0 (m/s)"."""
    entry = parameter(name)
    if signed_wind(name):
        return f"{symbol(name)} (kt, headwind or tailwind)"
    unit = unit_text(entry["units"]) if entry else ""
    return f"{symbol(name)} ({unit})" if unit else symbol(name)
