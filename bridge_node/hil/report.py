"""Reports of played scenarios: lines for the terminal and JUnit XML for CI (one test suite
per scenario, one test case per expectation, the measured values in the failure message)."""
from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from bridge_node.hil.player import ScenarioResult
from bridge_node.common.output_files import OutputFile


def result_lines(result: ScenarioResult) -> list[str]:
    """A scenario's verdict and one line per expectation with what was measured."""
    lines = [f"{'PASS' if result.passed else 'FAIL'}  {result.name} ({result.path}, {result.duration_s:.1f} s)"]
    for o in result.outcomes:
        lines.append(f"  {'pass' if o.passed else 'FAIL'}  {o.expectation.title()}: {o.measured}")
    sent = ", ".join(f"{role} {' '.join(f'{k} {v}' for k, v in counts.items())}"
                     for role, counts in result.sent.items() if counts)
    lines.append(f"  console sent: {sent or 'nothing'}")
    return lines


def node_lines(summary: dict | None) -> list[str]:
    """The node's own account at the end: each link's errors and reconnects, active alarms."""
    if summary is None:
        return ["node: no summary (attached, or it did not end cleanly)"]
    lines = [f"node: {link['name']}: errors {link['errors'] or 'none'}, reconnects {link['reconnects']}"
             for link in summary.get("links", [])]
    return lines + [f"node: active alarms at the end: {summary.get('alarms') or 'none'}",
                    f"node: session record {summary.get('record')}"]


def write_junit(results: list[ScenarioResult], path: Path) -> None:
    """JUnit XML of the results at ``path``."""
    root = ET.Element("testsuites", name="icebridge hil", tests=str(sum(len(r.outcomes) for r in results)),
                      failures=str(sum(not o.passed for r in results for o in r.outcomes)))
    for r in results:
        suite = ET.SubElement(root, "testsuite", name=r.name, tests=str(len(r.outcomes)),
                              failures=str(sum(not o.passed for o in r.outcomes)), time=f"{r.duration_s:.2f}",
                              file=r.path)
        for o in r.outcomes:
            case = ET.SubElement(suite, "testcase", classname=r.name, name=o.expectation.title(),
                                 time=f"{o.elapsed_s or 0.0:.3f}")
            if o.passed:
                ET.SubElement(case, "system-out").text = o.measured
            else:
                ET.SubElement(case, "failure", message=o.measured, type="expectation").text = o.measured
    ET.indent(root)
    path.parent.mkdir(parents=True, exist_ok=True)
    with OutputFile(path, "--junit") as tmp:
        ET.ElementTree(root).write(tmp, encoding="utf-8", xml_declaration=True)
