"""`srdda verify`: the command, its JSON document, its exit codes, and the manual documenting every case.

The cases' physics is what the cases check (each row against its tolerance); the runs that
other tests already make (free spin, free fall, nunchaku, the paper's swings) are not
repeated here: the command is run on the cases that no other test covers.
"""
import json
import re
from pathlib import Path

from click.testing import CliRunner

from srdda.apps.cli import main
from srdda.apps.verify import CASES, Case, row, run_case

REQUIRED = {"case", "quantity", "method", "ours", "reference", "rel_error"}
MANUAL = Path(__file__).resolve().parents[1] / "docs" / "verification.md"  # the manual's first page
GROUPS = sorted(MANUAL.with_suffix("").glob("*.md"))  # docs/verification/: a page per group of cases


def test_verify_json_of_the_fast_cases_passes():
    res = CliRunner().invoke(main, ["verify", "uniaxial-2d", "spring-mass-2d", "--quick", "--json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert set(doc) == {"rows"}
    assert {r["case"] for r in doc["rows"]} == {"uniaxial-2d", "spring-mass-2d"}
    for r in doc["rows"]:
        assert REQUIRED <= set(r), r
        assert r["passed"] is not False, r
    # every method the spring case is meaningful for has its period row
    periods = {r["method"] for r in doc["rows"] if r["quantity"] == "period (s)"}
    assert set(CASES["spring-mass-2d"].methods) <= periods


def test_quick_shortens_only_cases_registered_for_it():
    rows = run_case("free-spin-2d", quick=True, methods=("dda1",))
    assert {r["method"] for r in rows} == {"dda1"}
    assert any("step 2000" in r["quantity"] for r in rows) and all(r["passed"] for r in rows)
    assert not CASES["pendulum-2d"].quick  # its half period needs the whole swing


def test_a_failed_row_exits_with_1(monkeypatch):
    def off_by_one_percent(methods, quick):
        return [row("always-off", "x", "srdda", 1.01, 1.0, tolerance=1e-3)]
    monkeypatch.setitem(CASES, "always-off", Case("always-off", 2, "test", ("srdda",), off_by_one_percent, False))
    res = CliRunner().invoke(main, ["verify", "always-off"])
    assert res.exit_code == 1
    assert "FAIL" in res.stdout


def test_unknown_case_is_one_clear_error_listing_the_cases():
    res = CliRunner().invoke(main, ["verify", "free-spin-2d", "no-such-case"])
    assert res.exit_code == 2
    assert "unknown verification case 'no-such-case'" in res.output
    assert all(name in res.output for name in CASES)
    assert "Traceback" not in res.output


def test_row_error_is_absolute_where_the_reference_is_zero():
    r = row("c", "gap", "srdda", 2e-10, 0.0, tolerance=1e-9)
    assert (r["measure"], r["rel_error"], r["passed"]) == ("absolute", 2e-10, True)
    r = row("c", "period", "srdda", 1.5, -2.0, tolerance=0.2)
    assert (r["measure"], r["rel_error"], r["passed"]) == ("relative", 1.75, False)
    assert row("c", "info", "srdda", 1.0, 2.0, tolerance=None)["passed"] is None


def test_every_case_is_documented_in_the_manual():
    # one section per case on the page of its group, and every group page listed on the first page
    headings = [h for page in GROUPS for h in re.findall(r"^## `([\w-]+)`", page.read_text(encoding="utf-8"),
                                                          flags=re.MULTILINE)]
    assert set(CASES) <= set(headings), set(CASES) - set(headings)
    assert len(headings) == len(set(headings)), "a case documented twice"
    index = MANUAL.read_text(encoding="utf-8")
    assert GROUPS and all(f"(verification/{page.name})" in index for page in GROUPS)


def test_the_incline_case_holds_its_manual_tolerance_with_the_default_settings():
    # the suite's own incline test allows 0.5 %; the manual's row 1e-5. The default open-close
    # settings once let friction settle only to k_s·f0·w0 and `srdda verify` failed (2.5e-4 and
    # 9.7e-4) while the suite passed: this runs the manual's row (dda0: the three methods agree there)
    rows = run_case("incline-2d", quick=False, methods=("dda0",))
    assert rows and all(r["passed"] is not False for r in rows), [(r["quantity"], r["rel_error"]) for r in rows]
