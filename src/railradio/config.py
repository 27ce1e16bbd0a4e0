"""Config validation against the workflow's JSON schema, with messages a user can act on.

Only the workflow reads ``config/``; this module turns a loaded config mapping into a
validated one (schema defaults filled in) or raises :class:`ConfigError` naming the key,
the bad value and the allowed range, before any job runs.
"""

from __future__ import annotations

import copy
import os
from collections.abc import Mapping, MutableMapping
from typing import Any

import jsonschema
import yaml


class ConfigError(ValueError):
    """A config value violates the schema; the message names the key and the range."""


def load_schema(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Load a YAML/JSON schema file."""
    with open(path, encoding="utf-8") as fh:
        return yaml.safe_load(fh)


def _key_path(path: Any) -> str:
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "<top level>"


def describe_allowed(schema: dict[str, Any]) -> str:
    """A one-line human description of what a schema node allows."""
    parts: list[str] = []
    if "enum" in schema:
        parts.append("one of " + ", ".join(repr(v) for v in schema["enum"]))
    if "type" in schema:
        parts.append(f"type {schema['type']}")
    lo = [f"> {schema['exclusiveMinimum']}"] if "exclusiveMinimum" in schema else []
    lo += [f">= {schema['minimum']}"] if "minimum" in schema else []
    hi = [f"< {schema['exclusiveMaximum']}"] if "exclusiveMaximum" in schema else []
    hi += [f"<= {schema['maximum']}"] if "maximum" in schema else []
    if lo or hi:
        parts.append("value " + " and ".join(lo + hi))
    if "minItems" in schema:
        parts.append(f"at least {schema['minItems']} item(s)")
    if "maxItems" in schema:
        parts.append(f"at most {schema['maxItems']} item(s)")
    if "prefixItems" in schema:
        parts.append("items " + ", ".join(f"[{i}] {describe_allowed(p)}" for i, p in enumerate(schema["prefixItems"])))
    if "items" in schema and isinstance(schema["items"], dict):
        parts.append("each item " + describe_allowed(schema["items"]))
    if schema.get("uniqueItems"):
        parts.append("no repeated items")
    return "; ".join(parts) if parts else "see the schema"


def _prefixed(root: str, path: Any) -> str:
    if not root:
        return _key_path(path)
    return root + ("." + _key_path(path) if len(path) else "")


def _description_at(schema: dict[str, Any], path: Any) -> str:
    """The description of the deepest schema node on ``path`` that has one."""
    node, desc = schema, schema.get("description", "")
    for p in path:
        if isinstance(p, int):
            prefix = node.get("prefixItems", [])
            node = prefix[p] if p < len(prefix) else node.get("items", {})
        else:
            node = node.get("properties", {}).get(p, node.get("additionalProperties", {}))
        desc = node.get("description", desc) if isinstance(node, dict) else desc
        if not isinstance(node, dict):
            break
    return desc


def _fill_defaults(cfg: MutableMapping[str, Any], schema: dict[str, Any]) -> None:
    """Fill every missing key from the schema's defaults, creating missing sections (an
    object with ``properties`` and no default of its own is made of its keys' defaults)."""
    for name, sub in schema.get("properties", {}).items():
        if name not in cfg:
            if "default" in sub:
                cfg[name] = copy.deepcopy(sub["default"])
            elif sub.get("type") == "object" and "properties" in sub:
                cfg[name] = {}
        if isinstance(cfg.get(name), MutableMapping) and sub.get("type") == "object":
            _fill_defaults(cfg[name], sub)


def _is_integer(checker: Any, instance: Any) -> bool:
    """JSON's integers, without the floats of integral value JSON Schema admits (10.0): a
    count written as a float is a mistake (it fails later as an index or a range)."""
    return isinstance(instance, int) and not isinstance(instance, bool)


Validator = jsonschema.validators.extend(
    jsonschema.Draft202012Validator,
    type_checker=jsonschema.Draft202012Validator.TYPE_CHECKER.redefine("integer", _is_integer),
)
"""Draft 2020-12 validation with strict integers."""


def deep_merge(base: Mapping[str, Any], override: Mapping[str, Any]) -> dict[str, Any]:
    """A copy of ``base`` with ``override`` merged in (nested mappings merged key by key)."""
    out = copy.deepcopy(dict(base))
    for k, v in override.items():
        if isinstance(v, Mapping) and isinstance(out.get(k), Mapping):
            out[k] = deep_merge(out[k], v)
        else:
            out[k] = copy.deepcopy(v)
    return out


def validate_config(cfg: MutableMapping[str, Any], schema: dict[str, Any], root: str = "") -> MutableMapping[str, Any]:
    """Fill schema defaults into ``cfg`` in place and validate it.

    ``root`` prefixes the key paths in messages (for a sub-config such as a sensitivity
    case validated against one section's schema).

    Raises
    ------
    ConfigError
        On the first violation (deepest, most specific first), naming the key, the value,
        what is allowed and the key's description.
    """
    _fill_defaults(cfg, schema)
    validator = Validator(schema)
    errors = sorted(validator.iter_errors(cfg), key=lambda e: (-len(e.path), list(map(str, e.path))))
    if errors:
        lines = []
        for err in errors:
            node = err.schema if isinstance(err.schema, dict) else {}
            desc = _description_at(schema, err.absolute_path)
            if err.validator in ("required", "additionalProperties"):
                what = err.message
            else:
                what = f"{err.instance!r} is not allowed ({err.message})"
            lines.append(
                f"config key '{_prefixed(root, err.absolute_path)}': {what}. "
                f"Allowed: {describe_allowed(node)}." + (f" [{desc}]" if desc else "")
            )
        raise ConfigError("invalid configuration:\n  " + "\n  ".join(lines))
    return cfg
