"""The attack is a pipeline of typed stages: every class of its modules declares its state in
``__init__`` (or is a frozen dataclass), and the report, the cases and the plots take the
stages' typed results, never a campaign object."""

import ast
import dataclasses
import importlib
import inspect
import typing
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "bushenv"
# the stages, and what composes them: attack, campaign (matrix), zoo, replay
STAGE_MODULES = (
    "search/campaign",
    "search/campaign_config",
    "search/campaign_resolve",
    "search/campaign_search",
    "search/campaign_holds",
    "search/campaign_recheck",
    "search/campaign_cases",
    "search/campaign_report",
    "search/campaign_plots",
    "search/campaign_models",
    "search/matrix",
    "search/corpus",
    "search/case_file",
    "resolved",
    "commands/attack",
    "commands/campaign",
    "commands/replay",
    "commands/zoo",
    "zoo/cell",
    "zoo/study",
    "zoo/attack",
    "zoo/holds",
)
TYPED_RESULTS = ("campaign_report", "campaign_cases", "campaign_plots")


def _late_attributes(cls: ast.ClassDef) -> tuple[set[str], list[str]]:
    made, late = set(), []
    methods = [f for f in cls.body if isinstance(f, ast.FunctionDef)]
    init = [f for f in methods if f.name == "__init__"]
    for f in init + [f for f in methods if f.name != "__init__"]:
        for node in ast.walk(f):
            if (
                isinstance(node, ast.Attribute)
                and isinstance(node.ctx, ast.Store)
                and isinstance(node.value, ast.Name)
                and node.value.id == "self"
            ):
                if f.name == "__init__":
                    made.add(node.attr)
                else:
                    late.append(f"{cls.name}.{f.name}: self.{node.attr}")
    return made, late


@pytest.mark.parametrize("name", STAGE_MODULES)
def test_no_attribute_is_set_outside_init(name):
    tree = ast.parse((PACKAGE / f"{name}.py").read_text())
    late = []
    for cls in (n for n in ast.walk(tree) if isinstance(n, ast.ClassDef)):
        late += _late_attributes(cls)[1]
    assert not late, late


def test_the_late_attribute_check_can_fail():
    cls = ast.parse("class A:\n    def __init__(self):\n        self.a = 1\n"
                    "    def f(self):\n        self.b = 2\n").body[0]  # fmt: skip
    assert _late_attributes(cls) == ({"a"}, ["A.f: self.b"])


def test_there_is_no_campaign_class_and_the_stage_results_are_frozen():
    from bushenv.resolved import ResolvedModel
    from bushenv.search import campaign
    from bushenv.search.campaign_cases import Shrunk
    from bushenv.search.campaign_config import CampaignConfig
    from bushenv.search.campaign_recheck import Rechecked
    from bushenv.search.campaign_resolve import Resolved
    from bushenv.search.campaign_search import Searched

    assert not hasattr(campaign, "Campaign")
    for cls in (ResolvedModel, Resolved, Searched, Rechecked, Shrunk, CampaignConfig,
                campaign.Attacked):  # fmt: skip
        assert dataclasses.is_dataclass(cls) and cls.__dataclass_params__.frozen, cls


def _public_functions(module):
    for name, f in vars(module).items():
        if inspect.isfunction(f) and f.__module__ == module.__name__ and not name.startswith("_"):
            yield name, f


@pytest.mark.parametrize("name", TYPED_RESULTS)
def test_report_cases_and_plots_take_typed_results_not_a_campaign(name):
    module = importlib.import_module(f"bushenv.search.{name}")
    functions = dict(_public_functions(module))
    assert functions
    for fname, f in functions.items():
        hints = typing.get_type_hints(f)
        for param in inspect.signature(f).parameters:
            assert param != "campaign", f"{name}.{fname} takes a campaign"
            # every parameter is annotated, and by nothing that names a campaign object
            assert param in hints, f"{name}.{fname}({param}) has no annotation"
            assert "Campaign" not in str(hints[param]).replace("CampaignConfig", ""), (
                f"{name}.{fname}({param}: {hints[param]})"
            )


def _imported_names(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            names |= {a.name for a in node.names}
    return names


@pytest.mark.parametrize("name", ["search/matrix", "zoo/cell zoo/attack zoo/holds"])
def test_a_campaign_cell_and_a_zoo_member_compose_the_stages_not_a_run_of_their_own(name):
    names = set().union(*(_imported_names(PACKAGE / f"{n}.py") for n in name.split()))
    assert {"resolve_target", "run_search"} <= names
    # judging and searching are the stages' (no judge, evaluator or searcher built here)
    assert not names & {"build_judge", "judge_of", "BatchEvaluator", "get_searcher"}, names


def test_a_mimo_zoo_member_runs_the_attacks_search_not_one_of_its_own():
    names = _imported_names(PACKAGE / "zoo" / "attack.py")
    assert "family_search" in names
    assert not names & {"BatchEvaluator", "get_searcher", "SEARCHERS"}, names


def test_one_attack_runner_for_every_number_of_coordinates():
    """The attack command runs ``run_attack`` whatever the target's coordinates: no module of
    its own for three axes, no branch on them in the command."""
    search = PACKAGE / "search"
    assert not [p.name for p in search.glob("*planar*.py")]
    text = (PACKAGE / "commands" / "attack.py").read_text()
    assert "run_attack" in text and "planar" not in text
