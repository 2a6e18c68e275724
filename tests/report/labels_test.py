#!/usr/bin/python3
"""The report's one labeller (scripts/report/report_labels.py, issue 30): every group label of the
report names a value in the study's words. The oracles are independent of the labeller: the knot's
definition (1852 m per hour) for the winds, the manifest's levels for choices, and for the numbers the
rounding property (at most 4 significant digits, within half a unit of the 4th of the value).
Run by ctest (tests/report/CMakeLists.txt) with GESWEEP_BINARY set (the manifest's source).
"""
import math
import os
import random
import re
import sys
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts", "report"))
os.environ.pop("GESWEEP_COLUMNS_MANIFEST", None)  # the engine's manifest, not a test's file
import report_labels  # noqa: E402
import columns  # noqa: E402  (scripts/lib, on the path through report_labels)

# 1 kt in m/s, from its definition.
KNOT_MPS = 1852.0 / 3600.0
# The labels keep this many significant digits at most (issue 30).
MAX_DIGITS = 4
# A value written with 4 significant digits is within half a unit of its 4th digit: relative 5e-4 of
# its leading digit's magnitude at most (a little more than the value's own relative error bound).
HALF_UNIT_OF_FOURTH_DIGIT = 5e-4
# Studies store a wind in m/s to 6 decimals (studies/paper/landing_dispersion.toml: -15.433333).
STUDY_DECIMALS = 6
# The bound above is met up to the rounding of the float arithmetic that checks it (relative).
FLOAT_SLACK = 1e-9
# Random values drawn for the rounding property, over these decades.
RANDOM_VALUES = 2000
DECADES = (-3, 5)


def significant_digits(text):
    mantissa = re.split("[eE]", text.lstrip("-"))[0]
    digits = mantissa.replace(".", "").lstrip("0")
    return len(digits if "." in mantissa else digits.rstrip("0"))


class Numbers(unittest.TestCase):
    def test_known_values(self):
        for value, text in ((32.0208, "32.02"), (13.373, "13.37"), (0.7882, "0.7882"), (2.5935, "2.594"),
                            (2000, "2000"), (15.0000004, "15"), (0.0125, "0.0125"), (-7.716667, "-7.717"),
                            (1e-6, "1e-06"), (123456.0, "1.235e+05"), (0, "0")):
            self.assertEqual(report_labels.number(value), text, value)
        self.assertEqual(report_labels.number(math.nan), "—")

    def test_rounding_property(self):
        rng = random.Random(30)
        for _ in range(RANDOM_VALUES):
            value = rng.choice((-1, 1)) * 10 ** rng.uniform(*DECADES)
            text = report_labels.number(value)
            self.assertLessEqual(significant_digits(text), MAX_DIGITS, (value, text))
            scale = 10 ** math.floor(math.log10(abs(value)))
            self.assertLessEqual(abs(float(text) - value), HALF_UNIT_OF_FOURTH_DIGIT * scale * (1 + FLOAT_SLACK),
                                 (value, text))


class Values(unittest.TestCase):
    def test_winds_in_knots_with_their_direction(self):
        # docs/model.md section 9: wind_20ft_mps is the mean wind's u_g, negative for a headwind.
        for knots, sign, words in ((15, -1, "headwind"), (30, -1, "headwind"), (10, 1, "tailwind"), (7.5, -1, "headwind")):
            stored = round(sign * knots * KNOT_MPS, STUDY_DECIMALS)
            self.assertEqual(report_labels.value_label("wind_20ft_mps", stored), f"W20 = {knots:g} kt {words}")
        self.assertEqual(report_labels.value_label("wind_20ft_mps", 0.0), "W20 = calm")
        self.assertEqual(report_labels.axis_label("wind_20ft_mps"), "W20 (kt, headwind or tailwind)")

    def test_only_a_mean_wind_signed_as_u_g_is_a_head_or_tailwind(self):
        signed = [p["name"] for p in columns.manifest()["design"] if report_labels.signed_wind(p["name"])]
        self.assertEqual(signed, ["wind_20ft_mps"])
        # A gust's amplitude is along its axis, not a headwind: its value in its unit.
        self.assertEqual(report_labels.value_label("gust_amplitude_mps", 3.048), "v_m = 3.048 m/s")

    def test_levels_and_booleans_in_words(self):
        self.assertEqual(report_labels.value_label("h_derivatives", 1), "with h-derivatives")
        self.assertEqual(report_labels.value_label("h_derivatives", 0), "without h-derivatives")
        levels = columns.manifest()["design"]
        cdh = next(p for p in levels if p["name"] == "cdh")["levels"]
        for code, level in enumerate(cdh):
            self.assertEqual(report_labels.value_label("cdh", code), f"cdh = {level}")
        # The archive's own levels win over the manifest's.
        self.assertEqual(report_labels.value_label("cdh", 1, ["a", "b"]), "cdh = b")

    def test_every_parameter_of_the_manifest_is_labelled_with_four_digits_at_most(self):
        for parameter in columns.manifest()["design"]:
            with self.subTest(parameter=parameter["name"]):
                text = report_labels.value_label(parameter["name"], 1.23456789)
                numbers = re.findall(r"\d+(?:\.\d+)?", text.split("=", 1)[-1])
                self.assertTrue(all(significant_digits(n) <= MAX_DIGITS for n in numbers), text)
                self.assertNotIn("1.23456789", text)

    def test_a_key_joins_its_values(self):
        key = {"wind_20ft_mps": round(-30 * KNOT_MPS, STUDY_DECIMALS), "h_derivatives": 1.0, "speed_mps": 32.0208}
        self.assertEqual(report_labels.key_label(key), "W20 = 30 kt headwind, with h-derivatives, u0 = 32.02 m/s")


if __name__ == "__main__":
    unittest.main(verbosity=2)
