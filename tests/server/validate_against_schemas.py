#!/usr/bin/env python3
"""Checks the API's JSON Schemas (proto/schema/) with a real JSON Schema 2020-12 validator (python3-jsonschema):
each schema is valid, the shipped example jobs and everything texwarp_wire_samples writes (canonical jobs, statuses,
a page, a problem, a blob answer, real job results and report.json files) conform, so do the reports `texwarp check`
prints (when the CLI is given), and the documents the codec refuses are refused by the schema as well.
Usage: validate_against_schemas.py WIRE_SAMPLES_BINARY SOURCE_DIR [TEXWARP_CLI]. Exit 77: skipped."""
import glob
import json
import os
import subprocess
import sys
import tempfile
import warnings

try:
    import jsonschema
except ImportError:
    print("python3-jsonschema is not installed: skipped")
    sys.exit(77)

warnings.simplefilter("ignore", DeprecationWarning)
samples_binary, source = sys.argv[1], sys.argv[2]
cli = sys.argv[3] if len(sys.argv) > 3 else None
schema_dir = os.path.join(source, "proto", "schema")
schemas = {}
for path in glob.glob(os.path.join(schema_dir, "*.schema.json")):
    with open(path) as f:
        doc = json.load(f)
    jsonschema.Draft202012Validator.check_schema(doc)
    schemas[os.path.basename(path)] = doc
store = {doc["$id"]: doc for doc in schemas.values()}


def validator(name):
    schema = schemas[name]
    resolver = jsonschema.RefResolver.from_schema(schema, store=store)
    return jsonschema.Draft202012Validator(schema, resolver=resolver)


failures = []
checked = 0


def errors_of(name, doc):
    # Each schema's $id is its file name and its $refs name the files beside it ("job.schema.json",
    # "report.schema.json#/$defs/jobReport"), so they resolve through `store` and, within each, "#/$defs/…" too.
    return list(validator(name).iter_errors(doc))


def expect(name, path, valid):
    global checked
    with open(path) as f:
        doc = json.load(f)
    errors = sorted(errors_of(name, doc), key=lambda e: list(e.path))
    checked += 1
    if valid and errors:
        failures.append(f"{os.path.basename(path)} does not conform to {name}: {errors[0].message} at "
                        f"{'/'.join(str(p) for p in errors[0].absolute_path)}")
    if not valid and not errors:
        failures.append(f"{os.path.basename(path)} conforms to {name} but the codec refuses it")


examples = [p for p in glob.glob(os.path.join(source, "examples", "*.json")) if "job" in os.path.basename(p)]
if not examples:
    failures.append("no examples/*job*.json")
for path in examples:
    expect("job.schema.json", path, True)

with tempfile.TemporaryDirectory() as out:
    subprocess.run([samples_binary, out], check=True)
    kinds = {"job-": "job.schema.json", "status-": "job-status.schema.json", "page": "job-page.schema.json",
             "result-": "job-result.schema.json", "problem": "problem.schema.json", "blob": "blob.schema.json",
             "report-": "report.schema.json", "invalid-": "job.schema.json",
             "batch-status": "job-batch-status.schema.json", "batch-jobs": "job-batch.schema.json",
             "nodes": "node-list.schema.json"}
    for path in sorted(glob.glob(os.path.join(out, "*.json"))):
        base = os.path.basename(path)
        for prefix, name in kinds.items():
            if base.startswith(prefix):
                expect(name, path, not base.startswith("invalid-"))
                break
        else:
            failures.append(f"{base}: no schema for it")

# `texwarp check`: valid feature files (the field and a baseline, gradient features) and a refused one (exit 2).
if cli:
    with tempfile.TemporaryDirectory() as out:
        refused = os.path.join(out, "refused.json")
        with open(refused, "w") as f:
            json.dump({"features": [{"source": [1, 2], "target": [3, 4]}, {"source": [1, 2], "target": [5, 4]}]}, f)
        runs = [(os.path.join(source, "examples", "swirl-features.json"), "field", 0),
                (os.path.join(source, "examples", "swirl-features.json"), "tps", 0),
                (os.path.join(source, "examples", "astronaut-features.json"), "field", 0),
                (refused, "field", 2)]
        for k, (features, method, code) in enumerate(runs):
            run = subprocess.run([cli, "check", "--features", features, "--method", method, "--backend", "cpu",
                                  "--grid-step", "32"], capture_output=True, text=True)
            if run.returncode != code:
                failures.append(f"texwarp check {os.path.basename(features)} --method {method}: exit {run.returncode}")
                continue
            path = os.path.join(out, f"check-{k}.json")
            with open(path, "w") as f:
                f.write(run.stdout)
            expect("report.schema.json", path, True)

for f in failures:
    print("FAIL:", f)
print(f"{checked} documents checked against {len(schemas)} schemas, {len(failures)} failures")
sys.exit(1 if failures else 0)
