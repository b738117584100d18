"""The slug design's reference flood from a schedule (a study's SP flood): Eq. 4.10's reference concentrations and
slug sizes are read off its SP slug and polymer drive (values typed from Table 2.5), the designed schedule keeps the
chemical mass c * s of the reference slugs, and a flood without an SP slug or a polymer drive is refused by name."""

import pytest

from spflow.core.errors import ParameterError
from spflow.plugins.slug_design.slug_schedule import REFERENCE, SlugReference, slug_schedule
from spflow.plugins.slug_design.stage import SlugDesign


def test_reference_of_bcf1():
    ref = SlugReference.from_schedule("BCF1")  # Table 2.5: SP 0.5 PV 6780/3300 ppm at 9400 TDS, P 1.01 PV 3300 ppm
    assert (ref.surfactant_ppm, ref.sp_polymer_ppm, ref.s_sp, ref.sp_tds_ppm) == (6780.0, 3300.0, 0.5, 9400.0)
    assert (ref.polymer_ppm, ref.s_p, ref.p_tds_ppm, ref.water_tds_ppm) == (3300.0, 1.01, 9400.0, 9400.0)
    assert SlugReference.from_json(ref.to_json()) == ref


def test_designed_slugs_keep_the_reference_mass():
    ref = SlugReference.from_schedule("BCF2")  # SP 0.25 PV 6780/2500 ppm at 17500 TDS, P 0.5 PV 2500 ppm at 9400
    sched = slug_schedule(0.3, 0.4, 0.2, total_pv=5.0, reference=ref)
    _, htds, sp, p, _ = sched.slugs
    assert htds.salinity_ppm == 17500.0 and sp.salinity_ppm == 17500.0 and p.salinity_ppm == 9400.0
    assert sp.surfactant_ppm * 0.4 == pytest.approx(6780.0 * 0.25)
    assert sp.polymer_ppm * 0.4 == pytest.approx(2500.0 * 0.25)
    assert p.polymer_ppm * 0.2 == pytest.approx(2500.0 * 0.5)
    # Table 4.2's reference is unchanged: 0.25 PV slugs of 6780 / 2500 ppm
    thesis = slug_schedule(0.3, 0.4, 0.2, total_pv=5.0)
    assert thesis.slugs[3].polymer_ppm * 0.2 == pytest.approx(REFERENCE.polymer_ppm * 0.25)


def test_a_flood_without_sp_slug_or_drive_is_refused():
    polymer = {"name": "poly7", "slugs": [{"pv": 1.2, "salinity_ppm": 9400}, {"pv": 0.8, "salinity_ppm": 9400,
                                                                              "polymer_ppm": 1500}]}
    with pytest.raises(ParameterError, match="reference flood 'poly7' has no surfactant slug"):
        SlugReference.from_schedule(polymer)
    no_drive = {"name": "sp", "slugs": [{"pv": 1.0, "salinity_ppm": 9400},
                                        {"pv": 0.5, "salinity_ppm": 9400, "surfactant_ppm": 5000}]}
    with pytest.raises(ParameterError, match="parameter 'reference_flood'.*no polymer drive"):
        SlugDesign(reference_flood=no_drive)
