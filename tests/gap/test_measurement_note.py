"""A coreflood whose measurement model is not wholly in its data: the diagnosis names it and prints the model its
likelihood then uses (the documented lab defaults where the data are silent), instead of assuming it silently."""

from dataclasses import fields

from spflow.plugins.gap.observed import load_experiments, measurement_note
from spflow.synthetic import NoiseModel, make_coreflood


def test_a_coreflood_without_its_measurement_model_is_named_with_the_model_used():
    full = make_coreflood("BCF1", {}, noise=NoiseModel(), seed=1, cells=20)
    silent = full.copy()
    silent.attrs = {k: v for k, v in full.attrs.items() if not k.startswith("noise_")} | {
        "experiment": "lab_flood", "noise_dead_volume_ml": 0.5}
    assert measurement_note(load_experiments([full], 0.1)) is None
    note = measurement_note(load_experiments([full, silent], 0.1))
    assert "lab_flood" in note and "BCF1" not in note
    # the values used: the one the data give, the dataclass's defaults for the rest
    defaults = {f.name: f.default for f in fields(NoiseModel)}
    assert "dead_volume_ml = 0.5" in note
    for name, value in defaults.items():
        if name != "dead_volume_ml":
            assert f"{name} = {value:g}" in note
