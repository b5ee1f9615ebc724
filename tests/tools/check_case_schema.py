"""The weld case's JSON Schema (`rsw config schema --format json-schema`) against the
shipped cases: each validates; copies with a misspelt key, a number without digits, a
level out of range, an unknown choice and a table row of three columns do not.

Usage: /usr/bin/python3 check_case_schema.py RSW SOURCE_DIR   (Debian's python3-jsonschema, python3-yaml)
"""
import copy
import glob
import json
import os
import subprocess
import sys

import jsonschema
import yaml

rsw, source = sys.argv[1], sys.argv[2]
schema = json.loads(subprocess.run([rsw, "config", "schema", "--format", "json-schema"], check=True,
                                   capture_output=True, text=True).stdout)
jsonschema.Draft7Validator.check_schema(schema)
validator = jsonschema.Draft7Validator(schema)

failures = []
cases = sorted(glob.glob(os.path.join(source, "validation", "*", "weld.yaml")))
if len(cases) < 3:
    failures.append(f"found {len(cases)} shipped cases, expected the three of validation/*/weld.yaml")
for path in cases:
    with open(path) as f:
        case = yaml.safe_load(f)
    errors = [e.message for e in validator.iter_errors(case)]
    if errors:
        failures.append(f"{path}: {errors[:3]}")

with open(os.path.join(source, "validation", "paper_case", "weld.yaml")) as f:
    paper = yaml.safe_load(f)


def mutated(change):
    case = copy.deepcopy(paper)
    change(case)
    return case


bad = {
    "misspelt key": mutated(lambda c: c["schedule"].update({"cooling_time": c["schedule"].pop("cool_time")})),
    "unknown section": mutated(lambda c: c.update({"weldgun": {}})),
    "number without digits": mutated(lambda c: c["stack"]["sheets"][0].update({"thickness": "thick"})),
    "levels out of range": mutated(lambda c: c["mesh"]["weld_zone"].update({"levels": -1})),
    "unknown choice": mutated(lambda c: c.setdefault("solver", {}).update({"sheet_contact": "glued"})),
    "table row of three columns": mutated(lambda c: c["schedule"]["current"].append(["150 ms", "0 kA", "1"])),
}
for what, case in bad.items():
    if validator.is_valid(case):
        failures.append(f"a case with a {what} validates")

for failure in failures:
    print("FAIL:", failure)
print(f"{len(cases)} shipped cases valid, {len(bad)} broken copies refused" if not failures else "")
sys.exit(1 if failures else 0)
