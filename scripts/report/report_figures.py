"""The index of the report's figure families (docs/report.md, "The figure modules"): which module draws
which section, in page order, and what the section says when no archive holds its data.

Each family is one module `figures_<family>.py` whose `draw(archives, outdir)` returns the Figure
records it drew (none when the archives lack its data). A new family (say, the exceedance curves of a
subset-simulation product) is one module and one Family line here.
"""

import functools
from dataclasses import dataclass

import figures_dispersion
import figures_risk
import figures_landing
import figures_levels
import figures_maps
import figures_modes
import figures_open_loop
import figures_sensitivity


@dataclass
class Family:
    title: str    # the section's heading
    anchor: str   # its id in the page
    draw: object  # draw(archives, outdir) -> [Figure]
    absent: str   # the one line the section shows when no archive holds its data
    prefix: str   # the file names of its figures begin with this (a rerun removes the old ones)


def _sweeps(draw):
    """A family that reads sweep archives: the subset-simulation archives of `gesweep risk` are left out."""
    return lambda archives, outdir: draw([a for a in archives if not a.is_risk], outdir)


def _dispersion(archives, outdir):
    """The dispersion section: the Monte Carlo figures, then the landing-risk ones (figures_risk)."""
    return figures_dispersion.draw([a for a in archives if not a.is_risk], outdir) + figures_risk.draw(archives, outdir)


def _level_family(rated):
    wording = figures_levels.LEVEL_MAP_WORDING.get(rated.name)
    study = figures_levels.LEVEL_MAP_STUDIES.get(rated.name)
    absent = (f"No archive of this report holds the {rated.name} levels over height × speed"
              + (f"; `gesweep run {study}` writes them." if study else "."))
    return Family(wording[0] if wording else rated.section_title(), rated.name,
                  _sweeps(functools.partial(figures_levels.draw, rated=rated)), absent, rated.name + "_")


def families():
    """Every figure family in page order; the level maps (one per rated analysis of the column
    manifest) follow the stability map."""
    return ([Family("Stability map", "map", _sweeps(figures_maps.draw),
                    "No archive of this report holds the modes over height × speed (both swept); "
                    "`gesweep run studies/stability_map.toml` writes them.", "stability_map_")]
            + [_level_family(rated) for rated in figures_levels.rated_analyses()]
            + [Family("Root locus against height", "locus", _sweeps(figures_modes.draw),
                      "No archive of this report holds the modes along height; "
                      "`gesweep run studies/paper/modes_locus.toml` writes them.", "root_locus"),
               Family("Open-loop responses", "open_loop", _sweeps(figures_open_loop.draw),
                      "No archive of this report holds open-loop time series; "
                      "`gesweep run studies/paper/fig4_open_loop.toml` writes the paper's Fig. 4 study.", "open_loop_"),
               Family("Landing", "landing", _sweeps(figures_landing.draw),
                      "No archive of this report holds the time series of a landing outside turbulence; "
                      "`gesweep run studies/paper/landing.toml` writes the paper's landing.", "landing_"),
               Family("Sensitivity", "sensitivity", _sweeps(figures_sensitivity.draw),
                      "No archive of this report has global sensitivity indices; `gesweep run "
                      "studies/sensitivity_boundary.toml` and then `gesweep sensitivity ARCHIVE --output height_m` "
                      "write them.", "sensitivity_"),
               Family("Dispersion", "dispersion", _dispersion,
                      "No archive of this report has a dispersion product or a landing risk; `gesweep dispersion "
                      "ARCHIVE --group-by NAME` on a Monte Carlo study (studies/paper/landing_dispersion_sample.toml) "
                      "writes one, `gesweep risk studies/paper/landing_risk.toml -o ARCHIVE` the other.",
                      "dispersion_")])
