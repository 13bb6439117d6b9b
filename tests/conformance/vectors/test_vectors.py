"""The conformance vectors: well-formed, covering every rule, passing, and catching a broken implementation.

The vectors (``src/dynevent/conformance/vectors/*.json``) are written from docs/spec.md
rule by rule; these tests check the files against their JSON Schema, that
every numbered rule is cited by at least one vector, that ``dynevent vectors``
passes against dynevent in process and over the driver protocol, and that it
fails, with a diff naming the vector and the step, against a deliberately
broken driver (``tests/support/broken_driver.py``).
"""

from __future__ import annotations

import json
import re
import select
import shlex
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from importlib import resources
from pathlib import Path
from typing import Any

import jsonschema
import pytest

from dynevent.conformance import vectors
from dynevent.server.config import MORE_ERRORS
from dynevent.server.inputs import INPUT_TYPES
from dynevent.server.outputs import OUTPUT_TYPES
from dynevent.wire import _codec

ROOT = Path(__file__).resolve().parents[3]
SPEC = (ROOT / "docs" / "spec.md").read_text(encoding="utf-8")
#: Section 22 says what clients must not send: its rules are the client judge's
#: (tests/conformance/judge/test_clients.py), not a server's, so no server vector cites them.
CLIENT_RULES = re.findall(r"\*\*(R22\.\d+)\*\*", SPEC)
RULES = [rule for rule in re.findall(r"\*\*(R\d+\.\d+)\*\*", SPEC) if rule not in CLIENT_RULES]
VECTORS_FOLDER = resources.files("dynevent") / "conformance" / "vectors"
VECTOR_FILES = sorted(
    entry.name
    for entry in VECTORS_FOLDER.iterdir()
    if entry.name.endswith(".json") and not entry.name.endswith(".schema.json")
)
PYTHON = sys.executable
BROKEN_DRIVER = ROOT / "tests" / "support" / "broken_driver.py"
SUMMARY_LINE = re.compile(r"^(\d+) passed, (\d+) failed$", re.MULTILINE)
#: The last line of a run: what it took.
TOOK = re.compile(r"the run took \d+\.\d s")


def _rule_key(rule: str) -> tuple[int, ...]:
    return tuple(int(part) for part in rule[1:].split("."))


def _dynevent(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [PYTHON, "-m", "dynevent", "vectors", *args],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
        check=False,
    )


@pytest.fixture(scope="module")
def schema() -> Any:
    return json.loads((VECTORS_FOLDER / "vector.schema.json").read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def shipped() -> list[vectors.Vector]:
    return vectors.load_vectors()


# --------------------------------------------------------------------------- the files


def test_the_schema_is_a_valid_draft_2020_12_schema(schema: Any) -> None:
    jsonschema.Draft202012Validator.check_schema(schema)
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"


@pytest.mark.parametrize("name", VECTOR_FILES)
def test_vector_file_validates_against_the_schema(schema: Any, name: str) -> None:
    data = json.loads((VECTORS_FOLDER / name).read_text(encoding="utf-8"))
    errors = sorted(
        jsonschema.Draft202012Validator(schema).iter_errors(data), key=lambda error: error.json_path
    )
    assert not errors, "\n".join(f"{error.json_path}: {error.message}" for error in errors[:10])


def test_the_schema_refuses_a_malformed_vector(schema: Any) -> None:
    data = json.loads((VECTORS_FOLDER / "03-begin.json").read_text(encoding="utf-8"))
    first = data["vectors"][0]
    del first["steps"][0]["expect"][0]["message"]["fleet"]
    first["steps"][0]["input"]["now"] = 1.5
    first["rules"] = ["4.2"]
    paths = {error.json_path for error in jsonschema.Draft202012Validator(schema).iter_errors(data)}
    assert "$.vectors[0].rules[0]" in paths
    assert any(path.startswith("$.vectors[0].steps[0].input") for path in paths)
    assert any(path.startswith("$.vectors[0].steps[0].expect[0]") for path in paths)


def test_there_is_one_file_per_spec_section_and_one_for_rmf_ros2() -> None:
    sections = {int(rule[1:].split(".")[0]) for rule in RULES}
    numbered = {int(name.split("-")[0]) for name in VECTOR_FILES if name[:2].isdigit()}
    assert numbered == sections - {17}
    assert "compat-rmf_ros2.json" in VECTOR_FILES


def test_every_vector_cites_its_files_section(shipped: list[vectors.Vector]) -> None:
    for vector in shipped:
        filename = vector.source.rsplit("/", 1)[-1]
        section = "17" if filename.startswith("compat-") else str(int(filename.split("-")[0]))
        assert any(rule.split(".")[0] == f"R{section}" for rule in vector.rules), (vector.name, filename)


def test_every_spec_rule_is_covered_by_a_vector(shipped: list[vectors.Vector]) -> None:
    cited = {rule for vector in shipped for rule in vector.rules}
    missing = sorted(set(RULES) - cited, key=_rule_key)
    assert not missing, f"rules no vector cites: {missing}"


def test_every_cited_rule_exists(shipped: list[vectors.Vector]) -> None:
    unknown = sorted({rule for vector in shipped for rule in vector.rules} - set(RULES))
    assert not unknown, f"vectors cite rules docs/spec.md does not define: {unknown}"


def test_rmf_ros2_mode_has_its_own_vectors(shipped: list[vectors.Vector]) -> None:
    compat = [vector for vector in shipped if vector.source.endswith("compat-rmf_ros2.json")]
    assert len(compat) >= 5
    for vector in compat:
        assert vector.config.get("compatibility") == "rmf_ros2", vector.name
    cited = {rule for vector in compat for rule in vector.rules}
    assert {"R17.1", "R17.2", "R17.3"} <= cited


def test_wildcards_only_stand_for_open_wording(shipped: list[vectors.Vector]) -> None:
    """The wildcard "*" is kept for sentences the spec leaves open, never for a value it fixes."""
    open_wording = {"text", "why", "execution_failure", "errors"}

    def walk(value: Any, key: str, where: str) -> None:
        if value == vectors.WILDCARD:
            assert key in open_wording, f"{where}: wildcard in {key!r}"
        elif isinstance(value, dict):
            for inner, item in value.items():
                walk(item, inner, where)
        elif isinstance(value, list):
            for item in value:
                walk(item, key, where)

    for vector in shipped:
        for index, step in enumerate(vector.steps, start=1):
            for output in step.expect:
                walk(output, "", f"{vector.name} step {index}")


def _documented_records(heading: str) -> dict[str, set[str]]:
    """The record types of a table of docs/conformance.md, each with the fields it lists."""
    text = (ROOT / "docs" / "conformance.md").read_text(encoding="utf-8")
    section = text.split(f"\n### {heading}", 1)[1]
    first_table = re.search(r"^\| `type` \|.*\n\|[-|]*\n((?:\|.*\n)*)", section, re.MULTILINE)
    assert first_table, heading
    table: dict[str, set[str]] = {}
    for row in first_table[1].splitlines():
        kinds, fields = row.split(" | ")[:2]
        while re.search(r"\([^()]*\)", fields):  # what a bracket says of a field is not a field
            fields = re.sub(r"\([^()]*\)", "", fields)
        names = {name for name in re.findall(r"`([^`]*)`", fields) if re.fullmatch(r"[a-z_]+", name)}
        for kind in re.findall(r"`([a-z_]+)`", kinds):
            table[kind] = names
    return table


def test_every_input_a_driver_receives_is_documented_with_its_fields() -> None:
    """docs/conformance.md section 3.2 lists every input type the driver decodes, with all its fields."""
    documented = _documented_records("3.2 Inputs")
    machine = {kind: set(_codec._encoded(cls)) for kind, cls in INPUT_TYPES.items()}
    assert documented == machine


def test_every_output_is_documented_with_its_fields() -> None:
    documented = _documented_records("3.3 Outputs")
    machine = {kind: set(_codec._encoded(cls)) for kind, cls in OUTPUT_TYPES.items()}
    assert documented == machine


def _open_wording(output: dict[str, Any], clamped: bool) -> list[tuple[str, Any]]:
    """The values of ``output`` whose wording docs/conformance.md section 6 leaves open, by path.

    ``clamped``: the step reports a clamp (R12.2), so its warning entry's text is open."""
    kind = output["type"]
    found: list[tuple[str, Any]] = []
    if kind == "goal_rejected":
        rejection = output["rejection"]
        if rejection["reason"] != "seq_mismatch":
            found.append(("rejection.text", rejection["text"]))
        # the ninth error of R4.19 stands for the errors not listed: the spec fixes its wording
        errors = [error for error in rejection["errors"] if error != MORE_ERRORS]
        found += [(f"rejection.errors[{index}]", error) for index, error in enumerate(errors)]
        if rejection["errors"]:
            found.append(("rejection.execution_failure", rejection["execution_failure"]))
    if kind in ("goal_rejected", "answer_goal"):
        failure = (output.get("rejection") or output.get("result"))["execution_failure"]
        if " -- " in failure:  # a fixed string followed by open sentences (R4.8 to R4.10, R5.3, R6.1)
            found.append(("execution_failure", failure))
    if kind == "ignored":
        found.append(("why", output["why"]))
    if clamped and kind == "log" and output["entry"]["tier"] == "warning":
        found.append(("entry.text", output["entry"]["text"]))
    if clamped and kind == "publish_feedback":
        found += [("feedback.logs[].text", log["text"]) for log in output["feedback"]["logs"]]
    return found


def test_open_wording_is_always_a_wildcard(shipped: list[vectors.Vector]) -> None:
    """Where docs/conformance.md section 6 leaves the wording open, every vector expects "*": a vector
    that expects dynevent's own sentence there fails an implementation that keeps to the spec."""
    exact = []
    for vector in shipped:
        for index, step in enumerate(vector.steps, start=1):
            clamped = any(output["type"] == "stubborn_clamped" for output in step.expect)
            for output in step.expect:
                for path, value in _open_wording(output, clamped):
                    if value != vectors.WILDCARD:
                        exact.append(f"{vector.name} step {index}: {output['type']}.{path} = {value!r}")
    assert not exact, "\n".join(exact)


def test_open_wording_finds_what_it_must() -> None:
    """The check above reads each open place: a dynevent sentence in each is found."""
    rejection = {
        "reason": "description_invalid",
        "text": "t",
        "errors": ["e", MORE_ERRORS],
        "execution_failure": "Description parsing failure\n -- e",
    }
    found = _open_wording({"type": "goal_rejected", "goal_uuid": "", "rejection": rejection}, False)
    assert [path for path, _ in found] == [
        "rejection.text",
        "rejection.errors[0]",
        "rejection.execution_failure",
        "execution_failure",
    ]
    seq = {**rejection, "reason": "seq_mismatch", "errors": [], "execution_failure": ""}
    assert _open_wording({"type": "goal_rejected", "rejection": seq}, False) == []
    race = {"type": "answer_goal", "result": {"execution_failure": "race condition\n -- no"}}
    assert _open_wording(race, False) == [("execution_failure", "race condition\n -- no")]
    fixed = {"type": "answer_goal", "result": {"execution_failure": "race condition"}}
    assert _open_wording(fixed, True) == []
    assert _open_wording({"type": "ignored", "input": "tick", "why": "w"}, False) == [("why", "w")]
    log = {"type": "log", "entry": {"seq": 0, "tier": "warning", "unix_millis_time": 0, "text": "w"}}
    assert _open_wording(log, True) == [("entry.text", "w")]
    assert _open_wording(log, False) == []
    feedback = {"type": "publish_feedback", "feedback": {"logs": [log["entry"]]}}
    assert _open_wording(feedback, True) == [("feedback.logs[].text", "w")]


def test_vectors_are_short_and_summarised(shipped: list[vectors.Vector]) -> None:
    assert 60 <= len(shipped) <= 160
    for vector in shipped:
        assert vector.summary, vector.name
        assert len(vector.steps) <= 20, vector.name


# --------------------------------------------------------------------------- running


def test_every_vector_passes_in_process(shipped: list[vectors.Vector]) -> None:
    failures = [outcome for outcome in vectors.run_vectors(shipped, vectors.InProcessImplementation())]
    failed = [f"{outcome.vector.name}\n{outcome.failure.diff()}" for outcome in failures if outcome.failure]
    assert not failed, "\n\n".join(failed)


def test_cli_passes_in_process(shipped: list[vectors.Vector]) -> None:
    result = _dynevent()
    assert result.returncode == 0, result.stdout + result.stderr
    assert result.stdout.splitlines()[1].split() == ["rule", "vectors", "passed", "failed"]
    assert re.search(r"^R9\.3\s+\d+\s+\d+\s+0$", result.stdout, re.MULTILINE)
    summary = SUMMARY_LINE.findall(result.stdout)
    assert summary == [(str(len(shipped)), "0")]


def test_cli_passes_over_the_driver_protocol(shipped: list[vectors.Vector]) -> None:
    result = _dynevent("--impl", f"{PYTHON} -m dynevent.conformance.vectors.driver")
    assert result.returncode == 0, result.stdout + result.stderr
    assert SUMMARY_LINE.findall(result.stdout) == [(str(len(shipped)), "0")]


def test_a_broken_implementation_fails_with_a_diff() -> None:
    result = _dynevent("--impl", f"{PYTHON} {BROKEN_DRIVER}")
    assert result.returncode == 1, result.stdout + result.stderr
    assert "broken_driver" in result.stdout.splitlines()[0]
    assert re.search(r"^R9\.3\s+(\d+)\s+0\s+\1  FAIL$", result.stdout, re.MULTILINE)
    block = result.stdout.split(
        "FAIL cancel-keeps-the-robot-running (conformance/vectors/09-cancel.json)", 1
    )[1]
    assert "step 5: outputs differ" in block
    assert '"type":"goal_started"' in block
    # the outputs too many, each marked alone by its path; nothing expected is missing
    account = block.split("FAIL", 1)[0]
    assert "outputs[2]: not expected, got:" in account and '{"type":"answer_goal"' in account
    assert "missing" not in account
    assert all(len(line) <= 100 for line in result.stdout.splitlines())
    passed, failed = (int(number) for number in SUMMARY_LINE.findall(result.stdout)[0])
    assert passed > 0 and failed > 0


def test_filter_selects_by_name_glob_and_rule() -> None:
    result = _dynevent("--filter", "stateless-*")
    assert result.returncode == 0
    assert "6 passed, 0 failed" in result.stdout  # 20-stateless.json
    result = _dynevent("--filter", "request-*-id*", "--json")
    names = [json.loads(line)["name"] for line in result.stdout.splitlines()[:-1]]
    assert names and all(re.fullmatch(r"request-.*-id.*", name) for name in names)
    result = _dynevent("--filter", "R3.2", "--filter", "R10.4", "--json")
    records = [json.loads(line) for line in result.stdout.splitlines()]
    assert all("R3.2" in record["rules"] or "R10.4" in record["rules"] for record in records[:-1])
    assert records[-1]["vectors"] == len(records) - 1 >= 2


def test_filter_matching_nothing_is_a_usage_error() -> None:
    result = _dynevent("--filter", "no-such-vector")
    assert result.returncode == 2
    assert "no vector matches" in result.stderr


def test_json_output_is_one_object_per_vector_then_a_summary(shipped: list[vectors.Vector]) -> None:
    result = _dynevent("--json")
    assert result.returncode == 0
    records = [json.loads(line) for line in result.stdout.splitlines()]
    assert [record["type"] for record in records] == ["vector"] * len(shipped) + ["summary"]
    assert {record["name"] for record in records[:-1]} == {vector.name for vector in shipped}
    assert all(record["passed"] is True and record["failure"] is None for record in records[:-1])
    summary = records[-1]
    assert (summary["vectors"], summary["passed"], summary["failed"]) == (len(shipped), len(shipped), 0)
    assert summary["rules"]["R9.3"]["failed"] == 0


def test_json_output_of_a_failure_carries_the_diff() -> None:
    result = _dynevent("--impl", f"{PYTHON} {BROKEN_DRIVER}", "--json", "--filter", "cancel-keeps")
    assert result.returncode == 1
    records = [json.loads(line) for line in result.stdout.splitlines()]
    failing = [record for record in records if record["type"] == "vector" and not record["passed"]]
    assert failing and failing[0]["failure"]["step"] == 5
    assert failing[0]["failure"]["diff"].startswith("step 5: outputs differ")
    assert records[-1]["failed"] == len(failing)


# --------------------------------------------------------------------------- bad input


def _write(tmp_path: Path, name: str, content: str) -> Path:
    path = tmp_path / name
    path.write_text(content, encoding="utf-8")
    return path


def test_a_given_file_is_run(tmp_path: Path) -> None:
    example = json.loads((VECTORS_FOLDER / "03-begin.json").read_text(encoding="utf-8"))
    example["vectors"] = example["vectors"][:1]
    path = _write(tmp_path, "one.json", json.dumps(example))
    result = _dynevent(str(path))
    assert result.returncode == 0
    assert "1 passed, 0 failed" in result.stdout


def test_a_wrong_expectation_in_a_given_file_fails(tmp_path: Path) -> None:
    example = json.loads((VECTORS_FOLDER / "03-begin.json").read_text(encoding="utf-8"))
    example["vectors"] = example["vectors"][:1]
    example["vectors"][0]["steps"][0]["view"]["seq"] = 2
    path = _write(tmp_path, "wrong.json", json.dumps(example))
    result = _dynevent(str(path))
    assert result.returncode == 1
    assert "step 1: view differs" in result.stdout


@pytest.mark.parametrize(
    ("content", "where"),
    [
        ('{"vectors": [', "$"),
        ('{"vectors": {}}', "$.vectors"),
        ('{"vectors": [{"name": "x"}]}', "$.vectors[0]"),
        (
            '{"vectors": [{"name": "x", "summary": "s", "rules": ["R3.1"], "fleet": "f", "robot": "r",'
            ' "config": {}, "steps": [{"input": {"type": "begin"}, "expect": []}, {"input": {}}]}]}',
            "$.vectors[0].steps[1]",
        ),
        (
            '{"vectors": [{"name": "x", "summary": "s", "rules": [], "fleet": "f", "robot": "r",'
            ' "config": {}, "steps": [{"input": {"type": "begin", "description": "{}", "event_id": 1,'
            ' "now": 0, "interrupted": false}, "expect": []}]}]}',
            "$.vectors[0].rules",
        ),
    ],
)
def test_a_malformed_vector_file_is_a_located_usage_error(tmp_path: Path, content: str, where: str) -> None:
    path = _write(tmp_path, "bad.json", content)
    result = _dynevent(str(path))
    assert result.returncode == 2, result.stdout + result.stderr
    assert str(path) in result.stderr
    assert f": {where}" in result.stderr
    assert "Traceback" not in result.stderr
    assert result.stdout == ""


def _with_a_typo_in_an_expectation(tmp_path: Path) -> Path:
    example = json.loads((VECTORS_FOLDER / "03-begin.json").read_text(encoding="utf-8"))
    example["vectors"] = example["vectors"][:1]
    example["vectors"][0]["steps"][0]["expect"][0]["type"] = "publish_stauts"
    return _write(tmp_path, "typo.json", json.dumps(example))


def test_a_typo_in_an_expectation_is_a_vector_file_error_not_a_failure(tmp_path: Path) -> None:
    """The schema (a real validator) finds it: exit 2 naming the file, the vector and the path."""
    path = _with_a_typo_in_an_expectation(tmp_path)
    name = json.loads(path.read_text(encoding="utf-8"))["vectors"][0]["name"]
    result = _dynevent(str(path))
    assert result.returncode == 2, result.stdout + result.stderr
    assert f"{path}: $.vectors[0].steps[0].expect[0]" in result.stderr
    assert f"(vector {name!r})" in result.stderr and "(the vector file schema)" in result.stderr
    assert result.stdout == ""


def test_without_jsonschema_the_reader_alone_checks_and_says_so(tmp_path: Path) -> None:
    path = _with_a_typo_in_an_expectation(tmp_path)
    blocked = (
        "import sys; sys.modules['jsonschema'] = None; from dynevent.tools.cli import main; sys.exit(main())"
    )
    result = subprocess.run(
        [PYTHON, "-c", blocked, "vectors", str(path)], capture_output=True, text=True, timeout=60, check=False
    )
    assert "pip install 'dynevent[vectors]'" in result.stderr
    assert result.returncode == 1  # the typo reaches the run: the implementation is blamed
    assert "Traceback" not in result.stderr


def test_a_missing_vector_file_is_a_usage_error(tmp_path: Path) -> None:
    result = _dynevent(str(tmp_path / "absent.json"))
    assert result.returncode == 2
    assert "absent.json" in result.stderr and "Traceback" not in result.stderr


def test_an_implementation_that_cannot_start_is_a_usage_error(tmp_path: Path) -> None:
    result = _dynevent("--impl", str(tmp_path / "no-such-program"))
    assert result.returncode == 2
    assert "cannot start" in result.stderr and "Traceback" not in result.stderr


def test_an_implementation_that_does_not_speak_the_protocol_is_a_usage_error() -> None:
    result = _dynevent("--impl", f"{PYTHON} -c \"print('hello there')\"", "--timeout", "5")
    assert result.returncode == 2
    assert "Traceback" not in result.stderr


def test_the_rule_table_counts_each_vector_once_per_rule(shipped: list[vectors.Vector]) -> None:
    outcomes = [vectors.Outcome(vector, None) for vector in shipped]
    table = {tally.rule: tally for tally in vectors.rule_table(outcomes)}
    assert [tally.rule for tally in vectors.rule_table(outcomes)] == sorted(table, key=_rule_key)
    assert table["R3.2"].vectors == sum("R3.2" in vector.rules for vector in shipped)
    report = vectors.format_report(outcomes, "x")
    assert report.splitlines()[0] == "implementation: x"
    assert report.splitlines()[-1] == f"{len(shipped)} passed, 0 failed"


def test_every_divergence_has_a_vector() -> None:
    """Each section of docs/divergences.md is shown by at least one vector that names it."""
    text = (Path(__file__).resolve().parents[3] / "docs" / "divergences.md").read_text(encoding="utf-8")
    sections = set(re.findall(r"^## (D\d+)\.", text, flags=re.MULTILINE))
    assert sections, "docs/divergences.md lists no D-sections"
    covered = {item for vector in vectors.load_vectors() for item in vector.divergences}
    assert sections - covered == set(), f"divergences without a vector: {sorted(sections - covered)}"
    assert covered - sections == set(), f"vectors name unknown divergences: {sorted(covered - sections)}"


STALL = "import sys, time; sys.stdout.write('{\"ok'); sys.stdout.flush(); time.sleep(60)"


@pytest.mark.parametrize(
    ("impl", "extra", "problem"),
    [
        ("", [], "the implementation's command is empty"),
        ("'unclosed", [], "No closing quotation"),
        (f"{sys.executable} -c pass", [], "ended (exit code 0)"),
        (
            f"{sys.executable} -c \"import sys; sys.stdout.buffer.write(b'\\xff\\n'); sys.stdout.flush()\"",
            [],
            "not UTF-8",
        ),
        (  # a stall at hello: the start's bound (START_TIMEOUT), not --timeout
            f"{sys.executable} -c {shlex.quote(STALL)}",
            ["--timeout", "1"],
            f"did not answer within {vectors.START_TIMEOUT:g} s",
        ),
        (
            f"{sys.executable} -m dynevent.conformance.vectors.driver",
            ["--timeout", "nan"],
            "--timeout: expected seconds",
        ),
        (
            f"{sys.executable} -m dynevent.conformance.vectors.driver",
            ["--timeout", "-1"],
            "--timeout: expected seconds",
        ),
    ],
    ids=["empty", "bad-quoting", "exits", "not-utf8", "half-line-stall", "nan-timeout", "negative-timeout"],
)
def test_a_broken_implementation_is_a_clear_error_within_the_timeout(
    impl: str, extra: list[str], problem: str
) -> None:
    started = time.monotonic()
    result = _dynevent("--impl", impl, *extra)
    assert result.returncode == 2, result.stdout + result.stderr
    assert problem in result.stderr, result.stderr
    assert "Traceback" not in result.stderr
    assert time.monotonic() - started < 40  # the stalled one is cut at its start's 10 s, not after 60 s


@pytest.mark.parametrize("timeout", ["nan", "-1", "0", "inf", "1e9", "soon"])
def test_a_bad_timeout_is_a_usage_error_even_in_process(timeout: str) -> None:
    result = _dynevent("--timeout", timeout)
    assert result.returncode == 2 and "--timeout: expected" in result.stderr and result.stdout == ""


def test_a_sequence_diff_marks_one_extra_output_alone() -> None:
    expected = [{"type": "a"}, {"type": "b"}, {"type": "c", "uuid": "*"}, {"type": "d"}]
    got = [{"type": "a"}, {"type": "x"}, {"type": "b"}, {"type": "c", "uuid": "12ab"}, {"type": "e"}]
    assert vectors.align(expected, got) == [
        ("=", {"type": "a"}),
        ("+", {"type": "x"}),
        ("=", {"type": "b"}),
        ("=", {"type": "c", "uuid": "12ab"}),  # "*" matches any string
        ("-", {"type": "d"}),
        ("+", {"type": "e"}),
    ]
    assert vectors.align([{"type": "a"}, {"type": "b"}], [{"type": "b"}]) == [
        ("-", {"type": "a"}),
        ("=", {"type": "b"}),
    ]
    assert vectors.align([], []) == []


# --------------------------------------------------------------------------- a driver that misbehaves

MISBEHAVING = ROOT / "tests" / "support" / "misbehaving_driver.py"


def _misbehaving(
    tmp_path: Path, mode: str, at: int, *extra: str, once: bool = True, timeout: int = 1
) -> tuple[subprocess.CompletedProcess[str], float]:
    command = f"{PYTHON} {MISBEHAVING} {mode} {at}" + (f" --once {tmp_path / 'once'}" if once else "")
    started = time.monotonic()
    result = _dynevent("--impl", command, "--timeout", str(timeout), *extra)
    return result, time.monotonic() - started


#: The runner's timeout in the cases where the misbehaviour is not a wait: long enough for the
#: slowest honest machine to write and read 20 MB, so that the verdict is the limit's, never a timeout's.
NOT_A_WAIT = 30


@pytest.mark.parametrize(
    ("mode", "at", "problem"),
    [
        ("exit", 2, "the driver ended (exit code 3); its standard error ended with:"),
        ("exit", 20, "the driver ended (exit code 3)"),
        ("late", 20, "the driver did not answer within 1 s"),
        ("hang", 20, "the driver did not answer within 1 s"),
        ("garbage", 20, "the driver answered with"),
        ("flood", 20, "the driver answered with"),
        ("huge", 20, "the driver answered a line above"),
        ("closed", 20, "the driver closed its output and went on running: it was ended"),
        ("values", 20, "the driver answered a line of more than 1,000,000 values"),
    ],
)
def test_a_driver_that_breaks_once_fails_one_vector_and_the_rest_run(
    tmp_path: Path, shipped: list[vectors.Vector], mode: str, at: int, problem: str
) -> None:
    """Dies, stalls, answers late, answers garbage or floods: the vector it was answering fails, the
    driver is restarted, and every other vector runs and passes (a late answer is never read as the
    answer to a later request).  The report is whole and the exit status 1."""
    waits = mode in ("late", "hang")
    result, took = _misbehaving(tmp_path, mode, at, timeout=1 if waits else NOT_A_WAIT)
    assert result.returncode == 1, result.stdout + result.stderr
    assert SUMMARY_LINE.findall(result.stdout) == [(str(len(shipped) - 1), "1")], result.stdout
    assert problem in " ".join(result.stdout.split()), result.stdout
    assert "Traceback" not in result.stderr
    assert took < 60  # at most one timeout (1 s) and one restart


def test_a_driver_that_floods_its_standard_error_does_not_block_the_run(
    tmp_path: Path, shipped: list[vectors.Vector]
) -> None:
    result, _ = _misbehaving(tmp_path, "stderr", 20)
    assert result.returncode == 0, result.stdout + result.stderr[-500:]
    assert SUMMARY_LINE.findall(result.stdout) == [(str(len(shipped)), "0")]


def test_a_driver_that_writes_an_endless_error_line_does_not_grow_the_runner(
    tmp_path: Path, shipped: list[vectors.Vector]
) -> None:
    result, _ = _misbehaving(tmp_path, "endless", 20, timeout=NOT_A_WAIT)
    assert result.returncode == 0, result.stdout + result.stderr[-500:]
    assert SUMMARY_LINE.findall(result.stdout) == [(str(len(shipped)), "0")]


def test_a_drivers_name_of_any_text_is_printed_and_reported_escaped(tmp_path: Path) -> None:
    junit = tmp_path / "report.xml"
    result, _ = _misbehaving(tmp_path, "surrogate", 1, "--junit", str(junit), once=False, timeout=NOT_A_WAIT)
    assert result.returncode == 0, result.stdout + result.stderr[-500:]
    assert "Traceback" not in result.stderr
    assert "\\udc80" in result.stdout  # the lone surrogate, escaped where it is printed
    suite = ET.parse(junit).getroot().find("testsuite")  # parses: the name is made safe for XML
    assert suite is not None and suite.get("name", "").startswith("\\udc80\\u0007dynevent")


def test_a_driver_that_always_hangs_costs_three_timeouts_and_the_rest_are_not_run(
    tmp_path: Path, shipped: list[vectors.Vector]
) -> None:
    result, took = _misbehaving(tmp_path, "hang", 2, once=False)
    assert result.returncode == 1, result.stdout + result.stderr
    not_run = len(shipped) - vectors.MAX_STALLS
    assert f"0 passed, {vectors.MAX_STALLS} failed, {not_run} not run" in result.stdout
    assert f"{vectors.MAX_STALLS} vectors in a row timed out" in result.stdout
    assert took < 40  # three 1 s timeouts, not one per vector


def test_a_driver_that_never_answers_a_next_stops_the_run_at_three_timeouts_in_a_row(
    tmp_path: Path, shipped: list[vectors.Vector]
) -> None:
    """A driver that answers every step before a NEXT and hangs in it: each vector it hangs in counts
    towards the three in a row, though its first steps were answered (once 88 vectors timed out, one
    after the other, the count starting again at every answered step).  The run stops at the third,
    the rest not run, each vector's line printed as it ends, the last record what the run took."""
    result, took = _misbehaving(tmp_path, "next", 1, "--json", once=False)
    assert result.returncode == 1, result.stdout + result.stderr
    records = [json.loads(line) for line in result.stdout.splitlines()]
    *ran, summary = records
    timed_out = [
        record["failure"] is not None and "did not answer within 1 s" in record["failure"]["problem"]
        for record in ran
        if not record["not_run"]
    ]
    assert timed_out[-vectors.MAX_STALLS :] == [True] * vectors.MAX_STALLS, timed_out
    in_a_row = max(len(run) for run in "".join("x" if out else " " for out in timed_out).split(" "))
    assert in_a_row == vectors.MAX_STALLS, timed_out
    assert summary["not_run"] == len(shipped) - len(timed_out) > 0
    assert all(
        record["not_run"] == f"the run stopped: the driver stopped answering: {vectors.MAX_STALLS} vectors "
        "in a row timed out"
        for record in ran[len(timed_out) :]
    )
    assert 0 < summary["seconds"] <= took < 60  # three 1 s timeouts and their restarts, not one per vector


@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGTERM])
def test_json_prints_each_vector_as_it_ends_so_that_a_run_cut_short_keeps_them(
    tmp_path: Path, stop: signal.Signals
) -> None:
    """A driver that hangs at its 30th request, under --timeout 60: the vectors before it are printed
    as they end, long before the run would; the run stopped then (Ctrl-C or SIGTERM, though the run
    began with SIGINT ignored, as a shell's background job does: the driver is ended too), what it
    printed stays, and it exits 128 + the signal."""
    command = f"{PYTHON} {MISBEHAVING} hang 30"
    # a shell starts a background job with SIGINT ignored (and Python then installs no Ctrl-C of its own)
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        process = subprocess.Popen(
            [PYTHON, "-m", "dynevent", "vectors", "--json", "--timeout", "60", "--impl", command],
            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, cwd=ROOT,
        )  # fmt: skip
    finally:
        signal.signal(signal.SIGINT, previous)
    assert process.stdout is not None
    try:
        ready, _, _ = select.select([process.stdout], [], [], 30)
        assert ready and process.poll() is None, "no line within 30 s: the records wait for the run's end"
        first = json.loads(process.stdout.readline())
    finally:
        process.send_signal(stop)
        rest = process.communicate(timeout=30)[0]
    assert process.returncode == 128 + stop
    assert first["type"] == "vector" and first["passed"] is True, first
    assert all(json.loads(line)["type"] == "vector" for line in rest.splitlines())


def test_a_driver_slow_to_start_is_given_its_start_whatever_the_timeout(tmp_path: Path) -> None:
    """A program's start (an interpreter on a busy machine) is no answer of the protocol's: a driver
    whose hello comes after 1.5 s serves a run whose --timeout is 1 s (START_TIMEOUT), and a
    restarted one likewise (the hanging driver's three timeouts above depended on it)."""
    result, _ = _misbehaving(tmp_path, "late", 1, once=False)
    assert result.returncode == 0, result.stdout + result.stderr
    body, _, last = result.stdout.rstrip().rpartition("\n")
    assert body.endswith("passed, 0 failed") and TOOK.fullmatch(last), result.stdout[-300:]
    assert vectors.START_TIMEOUT >= 10


def test_a_driver_that_always_dies_stops_the_run_with_the_report_kept(
    tmp_path: Path, shipped: list[vectors.Vector]
) -> None:
    result, _ = _misbehaving(tmp_path, "exit", 2, "--json", once=False)
    assert result.returncode == 1, result.stdout + result.stderr
    records = [json.loads(line) for line in result.stdout.splitlines()]
    summary = records[-1]
    assert (summary["failed"], summary["not_run"]) == (vectors.MAX_BROKEN, len(shipped) - vectors.MAX_BROKEN)
    assert all(record["not_run"] for record in records[vectors.MAX_BROKEN : -1])


def test_a_driver_that_dies_at_hello_is_a_usage_error_naming_its_last_words(tmp_path: Path) -> None:
    result, _ = _misbehaving(tmp_path, "exit", 1, once=False)
    assert result.returncode == 2
    assert "ended (exit code 3)" in result.stderr and "giving up here" in result.stderr
    assert result.stdout == ""


def test_max_failures_and_exitfirst_stop_the_run(shipped: list[vectors.Vector]) -> None:
    broken = f"{PYTHON} {BROKEN_DRIVER}"
    for flags, failed in ((["-x"], 1), (["--max-failures", "2"], 2)):
        result = _dynevent("--impl", broken, *flags)
        assert result.returncode == 1
        found = re.search(r"^(\d+) passed, (\d+) failed, (\d+) not run$", result.stdout, re.MULTILINE)
        assert found, result.stdout
        assert int(found.group(2)) == failed
        assert sum(int(number) for number in found.groups()) == len(shipped)
        assert f"the run stopped after {failed} failed vector" in result.stdout
    assert "--max-failures: expected a number above 0" in _dynevent("--max-failures", "0").stderr


def test_junit_report_has_a_case_per_vector_with_the_failures(tmp_path: Path) -> None:
    import xml.etree.ElementTree as ET

    report = tmp_path / "vectors.xml"
    result = _dynevent("--impl", f"{PYTHON} {BROKEN_DRIVER}", "--junit", str(report), "-x")
    assert result.returncode == 1
    suite = ET.parse(report).getroot().find("testsuite")
    assert suite is not None
    cases = suite.findall("testcase")
    failures = [case for case in cases if case.find("failure") is not None]
    skipped = [case for case in cases if case.find("skipped") is not None]
    assert len(failures) == 1 and len(skipped) == int(suite.get("skipped", "-1")) > 0
    failure = failures[0].find("failure")
    assert failure is not None and failure.get("message", "").startswith("step ")
    assert "outputs[" in (failure.text or "")
    assert failures[0].get("classname", "").startswith("conformance/")
    unwritable = _dynevent("--junit", str(tmp_path / "no" / "such" / "dir.xml"))
    assert unwritable.returncode == 2 and "--junit" in unwritable.stderr


def test_a_difference_is_reported_by_the_path_of_the_field() -> None:
    expected = [
        {"type": "execute_goal", "goal_uuid": "*"},
        {"type": "answer_goal", "status": "aborted", "result": {"status": "", "id": 3}},
        {"type": "publish_status", "id": 3},
    ]
    got = [
        {"type": "execute_goal", "goal_uuid": "ab"},
        {"type": "answer_goal", "status": "aborted", "result": {"status": "x", "id": 3}, "extra": 1},
        {"type": "cancel_child", "id": 3},
    ]
    found = vectors.differences(expected, got, "outputs")
    assert [(d.path, d.kind) for d in found] == [
        ("outputs[1].result.status", "differs"),
        ("outputs[1].extra", "unexpected"),
        ("outputs[2]", "differs"),  # another kind of record: compared whole
    ]
    assert found[0].describe() == ['outputs[1].result.status: expected "", got "x"']
    assert vectors.differences([{"type": "a"}], [], "outputs")[0].describe() == [
        'outputs[0]: missing, expected: {"type":"a"}'
    ]
    long = vectors.Difference("outputs[0].text", "differs", "x" * 300, "y" * 300).describe(60)
    assert all(len(line) <= 60 for line in long) and long[0] == "outputs[0].text:"
    assert vectors.differences({"a": 1}, {"a": 1}, "view") == []


def test_json_output_of_a_failure_carries_each_difference() -> None:
    result = _dynevent("--impl", f"{PYTHON} {BROKEN_DRIVER}", "--json", "--filter", "cancel-keeps")
    failing = json.loads(result.stdout.splitlines()[0])["failure"]
    assert failing["differences"][0] == {
        "path": "outputs[2]",
        "kind": "unexpected",
        "expected": None,
        "got": failing["got"][2],
    }


# --------------------------------------------------------------------------- the runner's memory

#: A driver that answers every ``apply`` with one line of 60,000 ``publish_status`` records (the
#: runner's limits hold: 16 MiB, a million values), as in #52.
STATUSES_DRIVER = """
import json, sys
status = {"type": "publish_status", "message": {"dynamic_event_seq": 1, "dynamic_state": 1,
          "status": "standby", "id": 1, "time": {"sec": 1, "nanosec": 0}}}
answer = json.dumps({"ok": True, "outputs": [status] * 60_000, "view": None})
for line in sys.stdin:
    op = json.loads(line)["op"]
    if op == "hello":
        print(json.dumps({"ok": True, "implementation": "statuses", "protocol": 1}), flush=True)
    else:
        print(answer if op == "apply" else '{"ok": true}', flush=True)
"""


def test_the_runners_memory_is_within_ten_times_the_largest_line_it_reads(
    tmp_path: Path, shipped: list[vectors.Vector]
) -> None:
    """Two vectors each answered by a line of 8.9 MB, run and reported every way the command line
    reports (the text, JUnit, a JSON record at a time): the peak of traced memory stays within ten
    times the line (it was 18 times for one vector, before the failures kept bounded values and the
    first differences only)."""
    import tracemalloc

    from dynevent.wire import _json

    driver = tmp_path / "statuses.py"
    driver.write_text(STATUSES_DRIVER, encoding="utf-8")
    status = {"type": "publish_status", "message": {"dynamic_event_seq": 1, "dynamic_state": 1,
              "status": "standby", "id": 1, "time": {"sec": 1, "nanosec": 0}}}  # fmt: skip
    line = len(json.dumps({"ok": True, "outputs": [status] * 60_000, "view": None})) + 1
    implementation = vectors.ExternalImplementation(f"{PYTHON} {driver}", timeout=NOT_A_WAIT)
    tracemalloc.start()
    try:
        outcomes = list(vectors.run_vectors(shipped[:2], implementation))
        report = vectors.format_report(outcomes, implementation.name)
        vectors.junit_xml(outcomes, implementation.name)
        records = [len(_json.dumps(vectors.outcome_record(outcome))) for outcome in outcomes]
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
        implementation.close()
    assert all(outcome.failure is not None for outcome in outcomes)
    assert peak < 10 * line, f"{peak:,} bytes at the peak for a line of {line:,}"
    failure = outcomes[0].failure
    assert failure is not None and len(failure.differences) == vectors.MAX_DIFFERENCES
    found = vectors.differences(list(shipped[0].steps[0].expect), [status] * 60_000, "outputs")
    assert failure.more_differences == len(found) - vectors.MAX_DIFFERENCES
    assert f"... and {failure.more_differences:,} more differences" in report
    assert failure.got == f"<a value of more than {vectors.MAX_KEPT_VALUE:,} characters of JSON, not kept>"
    assert max(records) < 4 * vectors.MAX_KEPT_VALUE  # each value kept, within the bound
