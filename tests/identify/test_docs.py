"""docs/fit.md explains every option of every fittable model and every key of its model file."""

from pathlib import Path

import pytest

from bushenv.identify import fit_method, fittable_models
from bushenv.identify.options import flag_of, option_fields
from bushenv.models import MODELS

DOC = (Path(__file__).resolve().parents[2] / "docs" / "fit.md").read_text()


@pytest.mark.parametrize("name", fittable_models())
def test_every_option_flag_is_explained(name):
    missing = [
        flag_of(f.name)
        for f in option_fields(fit_method(name)[1])
        if f"`{flag_of(f.name)}`" not in DOC
    ]
    assert not missing, f"docs/fit.md does not explain {missing} of model {name}"


@pytest.mark.parametrize("name", fittable_models())
def test_every_model_file_key_is_in_the_schema(name):
    rows = [line for line in DOC.splitlines() if line.startswith(f"| {name} |")]
    cls = MODELS[name].model_class()
    text = "\n".join(rows)
    if name == "hybrid":
        text += "\n" + "\n".join(line for line in DOC.splitlines() if line.startswith("| nn |"))
    missing = [k for k in cls.param_names if f"`{k}`" not in text]
    assert not missing, f"docs/fit.md's .npz schema lacks {missing} of model {name}"
