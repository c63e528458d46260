#!/usr/bin/env python3
"""Bundles proto/schema/openapi.json with the JSON Schemas it refers to into one document whose every $ref is
internal (#/components/...): the OpenAPI document texwarpd serves at GET /v1/openapi.json.

Usage: bundle_openapi.py OPENAPI_JSON OUTPUT_JSON

The source documents refer to each other by file name, relative to their folder ("job.schema.json",
"report.schema.json#/$defs/jobReport"). Each <name>.schema.json becomes components.schemas.<Name> (its file name in
PascalCase: job-status.schema.json → JobStatus) without its $schema and $id, and each of its $defs entries becomes
components.schemas.<entry>, under its own name; a name taken twice fails the build. Key order, numbers and text are
kept as written (Python's json), so the served document reads like the source. Standard library only."""
import json
import os
import re
import sys

DEFS = re.compile(r"^/\$defs/([^/]+)(.*)$")


def component_name(file_name):
    return "".join(word[:1].upper() + word[1:] for word in file_name[: -len(".schema.json")].split("-"))


def main(openapi_path, output_path):
    folder = os.path.dirname(os.path.abspath(openapi_path))
    with open(openapi_path, encoding="utf-8") as f:
        api = json.load(f)
    files = sorted(n for n in os.listdir(folder) if n.endswith(".schema.json"))
    schemas = {}
    for name in files:
        with open(os.path.join(folder, name), encoding="utf-8") as f:
            schemas[name] = json.load(f)

    errors = []

    def target(ref, here):
        """The internal ref for `ref` written in the document `here` (a schema file name, or None: openapi.json)."""
        if ref.startswith("#/components/") and here is None:
            return ref
        file_part, _, fragment = ref.partition("#")
        doc = file_part or here
        if doc not in schemas:
            errors.append(f"{here or 'openapi.json'}: $ref \"{ref}\" names no schema file beside openapi.json")
            return ref
        match = DEFS.match(fragment)
        if match:
            if match.group(1) not in schemas[doc].get("$defs", {}):
                errors.append(f"{here or 'openapi.json'}: $ref \"{ref}\": {doc} has no $defs/{match.group(1)}")
            return "#/components/schemas/" + match.group(1) + match.group(2)
        return "#/components/schemas/" + component_name(doc) + fragment

    def rewrite(node, here):
        if isinstance(node, dict):
            return {k: (target(v, here) if k == "$ref" and isinstance(v, str) else rewrite(v, here))
                    for k, v in node.items()}
        if isinstance(node, list):
            return [rewrite(v, here) for v in node]
        return node

    bundled = rewrite(api, None)
    components = bundled.setdefault("components", {}).setdefault("schemas", {})
    owner = {key: "openapi.json" for key in components}

    def add(key, value, source):
        if key in components:
            errors.append(f"components.schemas.{key} comes from both {owner[key]} and {source}: rename one")
            return
        components[key] = value
        owner[key] = source

    for name, doc in schemas.items():
        body = {k: v for k, v in doc.items() if k not in ("$schema", "$id", "$defs")}
        add(component_name(name), rewrite(body, name), name)
        for key, value in doc.get("$defs", {}).items():
            add(key, rewrite(value, name), f"{name}#/$defs/{key}")

    if errors:
        for e in errors:
            print(f"bundle_openapi.py: {e}", file=sys.stderr)
        return 1
    text = json.dumps(bundled, indent=2, ensure_ascii=False) + "\n"
    os.makedirs(os.path.dirname(os.path.abspath(output_path)), exist_ok=True)
    # Written only when it changed, so that an unchanged bundle does not recompile the embedded documents.
    if os.path.exists(output_path):
        with open(output_path, encoding="utf-8") as f:
            if f.read() == text:
                return 0
    with open(output_path + ".tmp", "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(output_path + ".tmp", output_path)
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: bundle_openapi.py OPENAPI_JSON OUTPUT_JSON")
    sys.exit(main(sys.argv[1], sys.argv[2]))
