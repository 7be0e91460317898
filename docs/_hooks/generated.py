"""MkDocs hook: tables generated from the code, so they cannot go stale.

A page asks for a table with a marker line:

    <!-- generated: study-keys -->      every key a study file may hold, as the loader reads it
    <!-- generated: material-keys -->   every entry of a material file, its accepted units and SI range
    <!-- generated: spring-schema -->   every field of spring.json, from its JSON schema
    <!-- generated: axis-keys -->       the geometry keys that can be design axes

Study keys are found by loading every study in `studies/` (and the commented example in
`seadesign/design/requirements.py`) through the real loader while recording each key it asks for, its
type, default and bounds. Descriptions are the comments beside the keys in the study files (the default
study first), else the comment of the dataclass field; units are the key's suffix (the project's rule: a
key says its unit).
"""

from __future__ import annotations

import ast
import inspect
import json
import re
import textwrap
import tomllib
from contextlib import contextmanager
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
MARKER = re.compile(r"^<!-- generated: ([a-z-]+) -->$", re.MULTILINE)

# suffix -> unit, longest first
UNITS = [("_Nm_per_rad", "Nm/rad"), ("_kg_m2", "kg m^2"), ("_m_per_s", "m/s"), ("_percent", "%"), ("_mm", "mm"),
         ("_deg", "deg"), ("_Nm", "Nm"), ("_Hz", "Hz"), ("_rpm", "rpm"), ("_rad", "rad"), ("_kg", "kg"),
         ("_N", "N"), ("_m", "m"), ("_s", "s")]


def _unit(key: str) -> str:
    leaf = key.split(".")[-1]
    for suffix, unit in UNITS:
        if leaf.endswith(suffix):
            return unit
    parent = key.rsplit(".", 1)[0] if "." in key else ""
    if leaf in ("min", "max", "target") and parent:
        return _unit(parent)
    return "-"


def _toml_comments(text: str, prefix: str = "") -> dict[str, str]:
    """`table.key` -> the comment on its line and the comment-only lines right below it."""
    out: dict[str, str] = {}
    table, last = "", None
    for line in text.splitlines():
        stripped = line.strip()
        header = re.match(r"^\[([A-Za-z0-9_.\"]+)\]\s*(#\s*(.*))?$", stripped)
        if header:
            table = header.group(1).replace('"', "")
            last = table
            if header.group(3):
                out.setdefault(prefix + table, header.group(3).strip())
            continue
        item = re.match(r"^\"?([A-Za-z0-9_.]+)\"?\s*=.*?(#\s*(.*))?$", stripped)
        if item and not stripped.startswith("#"):
            key = f"{table}.{item.group(1)}" if table else item.group(1)
            last = prefix + key
            comment = item.group(3)
            if comment and last not in out:
                out[last] = comment.strip()
            elif last not in out:
                out[last] = ""
            continue
        if stripped.startswith("#") and last and line.startswith(" ") and out.get(last):
            out[last] += " " + stripped.lstrip("# ").strip()
        else:
            last = None if not stripped.startswith("#") or not line.startswith(" ") else last
    return out


def _field_comments(module) -> dict[str, str]:
    """`field` -> the comment beside it in the module's dataclasses (last one wins: only used as a fallback)."""
    out = {}
    for line in inspect.getsource(module).splitlines():
        m = re.match(r"^\s{4}([a-z_0-9]+): [^#=]+(=[^#]+)?#\s*(.+)$", line)
        if m:
            out[m.group(1)] = m.group(3).strip()
    return out


@contextmanager
def _recording(rows: dict[str, dict]):
    """Record every key a `Table` is asked for (kind, default, bounds, required)."""
    from seadesign.design import tomlcheck

    Table = tomlcheck.Table
    saved = {name: getattr(Table, name) for name in
             ("number", "integer", "string", "boolean", "number_list", "string_list", "table")}

    def wrap(kind):
        original = saved[kind]

        def recorded(self, name, *args, **kwargs):
            key = f"{self.where}.{name}" if self.where else name
            default = args[0] if args else kwargs.get("default", kwargs.get("optional", None))
            if kind == "table":
                required = not (args[0] if args else kwargs.get("optional", False))
                default = None
            elif kind == "number":
                required = kwargs.get("required", True) and default is None
            else:
                required = default is None and kind not in ("number_list", "string_list") or kind in (
                    "number_list", "string_list")
            bounds = " ".join(f"{word} {kwargs[b]:g}" for b, word in
                              (("gt", ">"), ("ge", ">="), ("lt", "<"), ("le", "<=")) if kwargs.get(b) is not None)
            if self.file.startswith(str(ROOT / "materials")):
                return original(self, name, *args, **kwargs)  # material files are documented apart
            row = rows.setdefault(key, {"kind": kind, "required": required, "default": default, "bounds": bounds})
            row["required"] = row["required"] and required
            return original(self, name, *args, **kwargs)

        return recorded

    for kind in saved:
        setattr(Table, kind, wrap(kind))
    try:
        yield
    finally:
        for name, fn in saved.items():
            setattr(Table, name, fn)


def _requirements_example() -> str:
    from seadesign.design import requirements

    doc = requirements.__doc__ or ""
    start = re.search(r"^ +\[requirements\]$", doc, re.MULTILINE).start()
    return textwrap.dedent(doc[start:].split("\n\n")[0])


def study_keys() -> str:
    from seadesign.design import requirements, study
    from seadesign.design.tomlcheck import Table

    rows: dict[str, dict] = {}
    with _recording(rows):
        for path in sorted((ROOT / "studies").glob("*.toml")):
            study.load_study(path)
        example = _requirements_example()
        requirements.read_requirements(Table(tomllib.loads(example)["requirements"], "example", "requirements"))
        requirements.read_requirements(Table({"k_Nm_per_rad": {"target": 40.0, "tolerance_percent": 10.0}},
                                             "example", "requirements"))
    comments: dict[str, str] = {}
    default_study = ROOT / "studies" / "wolfgang_knee.toml"
    sources = [default_study] + sorted(p for p in (ROOT / "studies").glob("*.toml") if p != default_study)
    for path in sources:
        for key, text in _toml_comments(path.read_text()).items():
            if text and not comments.get(key):
                comments[key] = text
    for key, text in _toml_comments(example).items():
        if text and not comments.get(key):
            comments[key] = text
    from seadesign.design import params

    fields = {**_field_comments(params), **_field_comments(requirements), **_field_comments(study)}
    # the design space is documented apart (any geometry key); deprecated and moved keys are listed apart
    deprecated = {"load_cases.lower_leg_m"}
    lines = ["| key | type | unit | default | bounds | what it is (from the study files' comments) |",
             "|---|---|---|---|---|---|"]
    for key in sorted(rows, key=_order):
        row = rows[key]
        if key.startswith("design_space.") or key in deprecated or row["kind"] == "table" and key in (
                "design_space",):
            continue
        if row["kind"] == "table":
            kind = "table"
        else:
            kind = {"number": "number", "integer": "integer", "string": "string", "boolean": "true/false",
                    "number_list": "list of numbers", "string_list": "list of names"}[row["kind"]]
        if row["required"]:
            default = "required"
        elif row["default"] is None:
            default = "optional (none)"
        elif isinstance(row["default"], bool):
            default = str(row["default"]).lower()
        else:
            default = f"`{row['default']!r}`"
        if key == "requirements.k_Nm_per_rad":
            default = "optional (none)"
        elif key.startswith("requirements.k_Nm_per_rad."):
            default = "`min` and/or `max`, or `target` with `tolerance_percent`"
        if key.endswith(".loads"):
            default = f"`{list(requirements.LOADS)}`"
        elif key.endswith(".objectives"):
            default = "`['mass']`; choose from " + ", ".join(f"`{o}`" for o in requirements.OBJECTIVES)
        text = comments.get(key) or fields.get(key.split(".")[-1], "")
        lines.append(f"| `{key}` | {kind} | {_unit(key) if kind != 'table' else ''} | {default} | {row['bounds']} | "
                     f"{_cell(text)} |")
    moved = ", ".join(f"`ranking.{old}` -> `{new}`" for old, new in requirements.MOVED.items())
    lines += ["", "Keys that are refused with an error naming their replacement: " + moved
              + "; `ranking.small_deflection_limit_rad` (no longer used). `load_cases.lower_leg_m` is deprecated "
                "(it repeats `robot.lower_leg_m`) and refused when it differs."]
    return "\n".join(lines)


def _order(key: str) -> tuple:
    top = ["name", "description", "material", "bearing_radius_mm", "geometry", "validity", "load_cases", "robot",
           "actuator", "mesh", "ranking", "requirements"]
    head = key.split(".")[0]
    return (top.index(head) if head in top else len(top), key.count(".") > 1, key)


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def axis_keys() -> str:
    from seadesign.design.space import AXIS_KEYS, INTEGER_KEYS, MATERIAL_KEY

    keys = ", ".join(f"`{k}`" + (" (integer)" if k in INTEGER_KEYS else "") for k in sorted(AXIS_KEYS))
    return f"Keys that can be design axes: {keys}, and `{MATERIAL_KEY}` (a list of material file stems)."


def material_keys() -> str:
    from seadesign.design import materials as m

    lines = ["| entry | required | accepted units | SI range (exclusive) | example (`materials/ninjaflex.toml`) |",
             "|---|---|---|---|---|"]
    example = tomllib.loads((ROOT / "materials" / "ninjaflex.toml").read_text())

    def ex(field):
        v = example.get(field)
        return f"{v['value']:g} {v['unit']}" if isinstance(v, dict) else "(not given)"

    lines.append("| `name` | yes | - | - | " + example["name"] + " |")
    for field, (units, (lo, hi)) in m._FIELDS.items():
        lines.append(f"| `{field}` | yes | {', '.join(f'`{u}`' for u in units)} | {lo:g} to {hi:g} | {ex(field)} |")
    for field in ("elongation_at_yield", "cyclic_strain_limit"):
        lines.append(f"| `{field}` | no | {', '.join(f'`{u}`' for u in m._STRAIN)} | 0 to 20 (strain) | {ex(field)} |")
    models = "; ".join(f"`{name}`: " + ", ".join(f"`{c}`" for c in cs) for name, cs in m.HYPERELASTIC_MODELS.items())
    lines.append(f"| `hyperelastic` | no | moduli {', '.join(f'`{u}`' for u in m._TO_PA)}; compressibilities "
                 f"{', '.join(f'`{u}`' for u in m._PER_PA)} | c10, d1 > 0 | (not given: neo-Hookean from E and nu) |")
    lines += ["", "Every quantity is a table `{ value = ..., unit = \"...\", source = \"...\" }`; `source` is required "
              "and says where the value comes from. `hyperelastic` is `{ model = ..., <constant> = { value, unit }, "
              f"source = ... }}` with the constants of its model: {models}."]
    return "\n".join(lines)


def spring_schema() -> str:
    schema = json.loads((ROOT / "seadesign" / "design" / "schemas" / "spring.schema.json").read_text())
    lines = [f"Schema `{schema.get('$id', '')}` ({schema.get('$schema', '')}): {schema.get('description', '')}", "",
             "| field | type | required | description |", "|---|---|---|---|"]

    def walk(node: dict, prefix: str, required: set[str]) -> None:
        for name, sub in node.get("properties", {}).items():
            key = f"{prefix}{name}"
            kind = sub.get("type") or ("enum: " + ", ".join(f"`{v}`" for v in sub["enum"]) if "enum" in sub else "")
            if isinstance(kind, list):
                kind = " or ".join(kind)
            lines.append(f"| `{key}` | {kind} | {'yes' if name in required else ''} | "
                         f"{_cell(sub.get('description', ''))} |")
            if sub.get("type") == "object" or "properties" in sub:
                walk(sub, key + ".", set(sub.get("required", [])))
            items = sub.get("items")
            if isinstance(items, dict) and "properties" in items:
                walk(items, key + "[].", set(items.get("required", [])))

    walk(schema, "", set(schema.get("required", [])))
    return "\n".join(lines)


GENERATORS = {"study-keys": study_keys, "material-keys": material_keys, "spring-schema": spring_schema,
              "axis-keys": axis_keys}


def on_page_markdown(markdown: str, page, config, files) -> str:  # noqa: ARG001 (MkDocs hook signature)
    return MARKER.sub(lambda m: GENERATORS[m.group(1)](), markdown)


if __name__ == "__main__":  # print the tables, e.g. to review them
    for name, gen in GENERATORS.items():
        print(f"## {name}\n\n{gen()}\n")
