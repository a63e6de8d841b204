"""The rig JSON's documented schema, one per `version`
(docs/formats/light-rig-<version>.schema.json, described in
docs/formats/light-rig.md). No part of Penumbra reads the file back; the
pipelines that do rely on these schemas. Shared by the schema's own test and
the demo's, which validates what today's Build Light Rig writes."""

import json
import os

import jsonschema

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def schema_path(version):
    return os.path.join(ROOT, "docs", "formats", f"light-rig-{version}.schema.json")


def schema(version):
    with open(schema_path(version)) as f:
        return json.load(f)


def validate(doc):
    """Raises jsonschema.ValidationError where `doc` breaks the schema of the
    version it names; a version without a schema is an error too."""
    version = doc.get("version") if isinstance(doc, dict) else None
    if type(version) is not int or not os.path.exists(schema_path(version)):
        raise jsonschema.ValidationError(f"no rig JSON schema for version {version!r}")
    jsonschema.Draft202012Validator(schema(version)).validate(doc)
