#!/usr/bin/python3
"""Checks a `spherechain check --junit` file against its --json (tests/cli/check.cmake), with a real XML
parser (xml.etree): one <testcase> per clip named as the clip, a <failure> exactly for the failing clips,
each failing event named in its failure's text, and the suite's counts consistent.

check_junit.py JUNIT.xml REPORT.json
"""
import json
import sys
import xml.etree.ElementTree as ET


def main():
    junit, report = sys.argv[1], json.load(open(sys.argv[2]))
    root = ET.parse(junit).getroot()
    if root.tag != "testsuites":
        sys.exit(f"{junit}: root <{root.tag}>, expected <testsuites>")
    suites = root.findall("testsuite")
    if len(suites) != 1:
        sys.exit(f"{junit}: {len(suites)} <testsuite>, expected 1")
    cases = {c.get("name"): c for c in suites[0].findall("testcase")}
    clips = {c["name"]: c for c in report["clips"]}
    if set(cases) != set(clips):
        sys.exit(f"testcases {sorted(cases)} != clips {sorted(clips)}")
    failing = 0
    for name, clip in clips.items():
        failure = cases[name].find("failure")
        if clip["failed"] != (failure is not None):
            sys.exit(f"clip {name}: failed={clip['failed']} but <failure> {'present' if failure is not None else 'absent'}")
        if failure is None:
            continue
        failing += 1
        for e in clip["events"]:
            if e["failed"] and e["name"] + " frames" not in failure.text:
                sys.exit(f"clip {name}: failing event {e['name']} not in the failure text:\n{failure.text}")
    for node in (root, suites[0]):
        if int(node.get("tests")) != len(clips) or int(node.get("failures")) != failing:
            sys.exit(f"<{node.tag}> counts tests={node.get('tests')} failures={node.get('failures')}, "
                     f"expected {len(clips)} and {failing}")
    print(f"{junit}: {len(clips)} testcases, {failing} failing: consistent with {sys.argv[2]}")


if __name__ == "__main__":
    main()
