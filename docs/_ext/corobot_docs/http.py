"""The HTTP API from the server's own OpenAPI document (`serving.webapp.create_app`'s
`openapi()`): every path and method with its summary, parameters, request body and answers,
then the schemas' fields."""

from __future__ import annotations

import json
import types

from corobot_docs.markdown import cell, table

METHODS = ("get", "post", "put", "patch", "delete")


def openapi() -> dict:
    """The document of an app around a stand-in runner (the document names no robot)."""
    from corobot_drake.serving.webapp import create_app

    return create_app(types.SimpleNamespace(robots={"corobot": None})).openapi()


def page() -> str:
    doc = openapi()
    operations = [(path, method, op) for path, ops in doc["paths"].items()
                  for method, op in ops.items() if method in METHODS]
    out = [f"{doc['info']['description'].strip()}\n\nGenerated from the server's OpenAPI "
           "document at each build (`docs/_ext/corobot_docs/http.py`); a running server "
           "serves the same at `/openapi.json`, browsable at `/docs`.",
           "## Endpoints\n\n" + table(("method", "path", "what"), [
               [method.upper(), f"`{path}`", cell(op.get("summary", ""))]
               for path, method, op in operations])]
    tags = dict.fromkeys(op.get("tags", ["other"])[0] for _, _, op in operations)
    for tag in tags:
        out.append(f"## {tag.capitalize()}")
        out += [_operation(path, method, op) for path, method, op in operations
                if op.get("tags", ["other"])[0] == tag]
    out.append("## Schemas\n\nThe bodies' and answers' JSON objects.")
    out += [_schema(name, schema) for name, schema in doc["components"]["schemas"].items()]
    return "\n\n".join(out) + "\n"


def _operation(path: str, method: str, op: dict) -> str:
    parts = [f"### {method.upper()} `{path}`", op.get("summary", "")]
    if op.get("description"):
        parts.append(op["description"].strip())
    params = op.get("parameters", [])
    if params:
        parts.append(table(("parameter", "in", "type", "required", "what"), [
            [f"`{p['name']}`", p["in"], _type(p.get("schema", {})),
             "yes" if p.get("required") else "no",
             cell(p.get("description", "") or p.get("schema", {}).get("description", ""))]
            for p in params]))
    body = op.get("requestBody", {}).get("content", {})
    for media, content in body.items():
        parts.append(f"Body ({media}): {_type(content.get('schema', {}))}.")
    parts.append("Answers: " + ", ".join(
        f"{code} {_answer(r)}" for code, r in op.get("responses", {}).items()) + ".")
    return "\n\n".join(p for p in parts if p)


def _answer(response: dict) -> str:
    schemas = [c.get("schema", {}) for c in response.get("content", {}).values()]
    kinds = [_type(s) for s in schemas if s]
    return response.get("description", "") + (f" ({', '.join(kinds)})" if kinds else "")


def _type(schema: dict) -> str:
    if "$ref" in schema:
        name = schema["$ref"].rsplit("/", 1)[-1]
        return f"[{name}](#{name.lower()}-schema)"
    if "anyOf" in schema:
        return " or ".join(_type(s) for s in schema["anyOf"])
    if schema.get("type") == "array":
        return f"array of {_type(schema.get('items', {}))}"
    if "enum" in schema:
        return "one of " + ", ".join(f"`{v}`" for v in schema["enum"])
    return schema.get("type", "any")


def _range(schema: dict) -> str:
    words = []
    for key, sign in (("minimum", ">="), ("exclusiveMinimum", ">"), ("maximum", "<="),
                      ("exclusiveMaximum", "<")):
        if key in schema:
            words.append(f"{sign} {schema[key]:g}")
    return " and ".join(words)


def _schema(name: str, schema: dict) -> str:
    head = f"### `{name}` (schema)"
    if schema.get("description"):
        head += "\n\n" + schema["description"].strip()
    props = schema.get("properties", {})
    if not props:
        return head + f"\n\n{_type(schema)}."
    required = set(schema.get("required", []))
    rows = [[f"`{field}`", _type(s), "yes" if field in required else "no",
             f"`{json.dumps(s['default'])}`" if "default" in s else "", _range(s),
             cell(s.get("description", ""))] for field, s in props.items()]
    return head + "\n\n" + table(("field", "type", "required", "default", "allowed", "what"),
                                 rows)
