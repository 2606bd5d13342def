"""Reads `scopekin verify --json` from stdin: a non-empty JSON array of objects, each with at
least the keys the CLI documents (case, reference, value, error, tolerance, pass)."""
import json
import sys

a = json.load(sys.stdin)
assert isinstance(a, list) and a, "expected a non-empty JSON array"
required = {"case", "reference", "value", "error", "tolerance", "pass"}
assert all(isinstance(o, dict) and required <= set(o) for o in a), "an entry lacks a required key"
