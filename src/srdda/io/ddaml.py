"""DDAML: the XML geometry and analysis files of DDA for Windows (Doolin's ntdda).

Elements are matched by local name (``Berkeley:Edgenodedist`` and
``Edgenodedist`` alike), as the original reader does. Joint and block
material types are taken in order of appearance, as in DDA for Windows.
Elements srdda does not support are warned about by name.
"""
from __future__ import annotations

import re
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from .ddainput import BlockMaterialSpec, DDAInput, DDAInputError, read_input_text

__all__ = ["read_ddaml"]


def _local(tag: str) -> str:
    return tag.rsplit("}", 1)[-1].split(":")[-1]


def _parse(path: Path) -> ET.Element:
    """The XML root; element prefixes without a namespace declaration (``Berkeley:`` alone) are dropped."""
    text = read_input_text(path)
    try:
        return ET.fromstring(text)
    except ET.ParseError as exc:
        if "unbound prefix" not in str(exc):
            raise DDAInputError(f"{path}: not a readable DDAML file ({exc})") from None
    try:
        return ET.fromstring(re.sub(r"<(/?)[A-Za-z_][\w.-]*:", r"<\1", text))
    except ET.ParseError as exc:
        raise DDAInputError(f"{path}: not a readable DDAML file ({exc})") from None


def _root(path: Path, section: str) -> ET.Element:
    root = _parse(path)
    for el in root.iter():
        if _local(el.tag) == section:
            return el
    raise DDAInputError(f"{path}: no <{section}> element")


def _floats(el: ET.Element, n: int | None, path: Path) -> list[float]:
    try:
        vals = [float(v) for v in (el.text or "").split()]
    except ValueError:
        raise DDAInputError(f"{path}: <{_local(el.tag)}> must hold numbers, got {el.text!r}") from None
    if n is not None and len(vals) != n:
        raise DDAInputError(f"{path}: <{_local(el.tag)}> needs {n} numbers, got {len(vals)}")
    return vals


def _attr(el: ET.Element, name: str, path: Path) -> str:
    value = el.get(name)
    if value is None:
        raise DDAInputError(f"{path}: <{_local(el.tag)}> needs the attribute {name!r}")
    return value


def _num_attr(el: ET.Element, name: str, path: Path) -> float:
    value = _attr(el, name, path)
    try:
        return float(value)
    except ValueError:
        raise DDAInputError(f"{path}: <{_local(el.tag)} {name}=...> must be a number, got {value!r}") from None


def _points(el: ET.Element, path: Path) -> list[list[float]]:
    return [_floats(p, 2, path) for p in el if _local(p.tag) == "Point"]


def _read_geometry(path: Path) -> dict:
    geo = _root(path, "Geometry")
    out: dict = {"joints": [], "types": [], "fixed": [], "load": [], "measured": [], "hole": [],
                 "matlines": [], "mattypes": [], "e00": None}
    for el in geo:
        name = _local(el.tag)
        if name == "Edgenodedist":
            out["e00"] = _num_attr(el, "distance", path)
        elif name == "Jointlist":
            for j in el:
                if _local(j.tag) == "Joint":
                    out["joints"].append(_floats(j, 4, path))
                    out["types"].append(int(_num_attr(j, "type", path)))
        elif name == "Fixedpointlist":
            for p in el:
                if _local(p.tag) == "Line":
                    out["fixed"].append(_floats(p, 4, path))
                elif _local(p.tag) == "Point":
                    x, y = _floats(p, 2, path)
                    out["fixed"].append([x, y, x, y])
        elif name in ("Loadpointlist", "Measuredpointlist", "Holepointlist"):
            out[{"L": "load", "M": "measured", "H": "hole"}[name[0]]] += _points(el, path)
        elif name == "Matlinelist":
            for ln in el:
                if _local(ln.tag) == "Line":
                    out["matlines"].append(_floats(ln, 4, path))
                    out["mattypes"].append(int(_num_attr(ln, "type", path)))
        else:
            warnings.warn(f"{path}: <{name}> is not supported (ignored)", stacklevel=3)
    if out["e00"] is None:
        raise DDAInputError(f"{path}: no <Edgenodedist distance=...> element")
    if not out["joints"]:
        raise DDAInputError(f"{path}: no <Joint> in <Jointlist>")
    return out


_FLAG_ELEMENTS = {"Autotimestep": "auto_time_step", "Planestrain": "plane_strain"}
_IGNORED = {"Writevertices", "Mintimestep", "Boltproperties", "Timehistory", "ContactDamping", "AConstants",
            "Gravity"}


def _read_analysis(path: Path, data: DDAInput) -> None:
    ana = _root(path, "Analysis")
    if ana.get("type") is not None:
        data.dynamic = ana.get("type") == "dynamic"
    for el in ana:
        name = _local(el.tag)
        if name == "Analysistype":
            data.dynamic = _attr(el, "type", path) == "dynamic"
        elif name == "Rotation":
            data.rotation = _attr(el, "type", path)
        elif name in _FLAG_ELEMENTS:
            setattr(data, _FLAG_ELEMENTS[name], _attr(el, "flag", path) == "yes")
        elif name == "Autopenalty":
            data.auto_penalty = _attr(el, "flag", path) == "yes"
            data.penalty_factor = _num_attr(el, "pfactor", path)
        elif name == "Numtimesteps":
            data.n_steps = int(_num_attr(el, "timesteps", path))
        elif name == "Maxtimestep":
            data.max_time_step = _num_attr(el, "maxtimestep", path)
        elif name == "Maxdisplacement":
            data.max_displacement_ratio = _num_attr(el, "maxdisplacement", path)
        elif name == "Saveinterval":
            data.save_interval = int(_num_attr(el, "step", path))
        elif name == "Opencloselimit":
            data.open_close_limit = int(_num_attr(el, "maxopenclose", path))
        elif name == "Gravaccel":
            data.gravity_acceleration = _num_attr(el, "value", path)
        elif name == "Blockmaterial":
            data.block_materials.append(_block_material(el, path))
        elif name == "Jointproperties":
            vals = {_local(c.tag): _floats(c, 1, path)[0] for c in el}
            data.joint_materials.append((vals.get("Friction", 0.0), vals.get("Cohesion", 0.0),
                                         vals.get("Tensile", 0.0)))
        elif name == "Loadpointlist":
            for lp in el:
                if _local(lp.tag) == "Loadpoint":
                    data.load_histories.append(_history(lp, path))
        elif name == "OCLimit":
            warnings.warn(f"{path}: <OCLimit> is not a keyword of DDA for Windows (its keyword is "
                          "<Opencloselimit>); ignored", stacklevel=3)
        elif name in _IGNORED:
            if name == "Gravity" and el.get("flag") != "yes":
                continue
            warnings.warn(f"{path}: <{name}> is not supported (ignored)", stacklevel=3)
        else:
            warnings.warn(f"{path}: unknown element <{name}> ignored", stacklevel=3)
    if data.rotation not in ("linear", "exact", "secondorder"):
        raise DDAInputError(f"{path}: <Rotation type={data.rotation!r}> must be linear, exact or secondorder")


def _block_material(el: ET.Element, path: Path) -> BlockMaterialSpec:
    vals = {_local(c.tag): _floats(c, None, path) for c in el}
    for key in ("Unitmass", "Unitweight", "Youngsmod", "Poissonratio"):
        if key not in vals or len(vals[key]) != 1:
            raise DDAInputError(f"{path}: <Blockmaterial> needs one number in <{key}>")

    def triple(key: str) -> tuple[float, float, float]:
        v = vals.get(key, [0.0, 0.0, 0.0])
        if len(v) != 3:
            raise DDAInputError(f"{path}: <{key}> needs 3 numbers, got {len(v)}")
        return (v[0], v[1], v[2])

    return BlockMaterialSpec(unit_mass=vals["Unitmass"][0], unit_weight=vals["Unitweight"][0],
                             young=vals["Youngsmod"][0], poisson=vals["Poissonratio"][0],
                             stress=triple("Istress"), strain=triple("Istrain"), velocity=triple("Ivelocity"),
                             damping=vals.get("Damping", [0.0])[0])


def _history(el: ET.Element, path: Path) -> np.ndarray:
    n = int(_num_attr(el, "numpoints", path))
    rows = [r.split() for r in (el.text or "").split(";") if r.strip()]
    try:
        table = np.array([[float(v) for v in r] for r in rows])
    except ValueError:
        raise DDAInputError(f"{path}: <Loadpoint> rows must be 't fx fy;'") from None
    if table.ndim != 2 or table.shape[1] != 3 or len(table) != n:
        raise DDAInputError(f"{path}: <Loadpoint numpoints={n}> holds {len(rows)} 't fx fy;' row(s)")
    return table


def read_ddaml(geometry: str | Path, analysis: str | Path | None = None) -> DDAInput:
    """Read a DDAML geometry / analysis pair, in the files' units.

    Without ``analysis`` only the geometry is read (no materials, no run
    parameters): :meth:`DDAInput.use_default_analysis` fills them.
    """
    gpath = Path(geometry)
    g = _read_geometry(gpath)
    data = DDAInput(
        source=gpath.name, edge_node_ratio=g["e00"],
        joints=np.array(g["joints"], dtype=float).reshape(-1, 4),
        joint_types=np.array(g["types"], dtype=np.int64),
        material_lines=np.array(g["matlines"], dtype=float).reshape(-1, 4),
        material_line_types=np.array(g["mattypes"], dtype=np.int64),
        fixed_lines=np.array(g["fixed"], dtype=float).reshape(-1, 4),
        load_points=np.array(g["load"], dtype=float).reshape(-1, 2),
        measured_points=np.array(g["measured"], dtype=float).reshape(-1, 2),
        hole_points=np.array(g["hole"], dtype=float).reshape(-1, 2),
    )
    if analysis is not None:
        _read_analysis(Path(analysis), data)
        data.source = f"{gpath.name}+{Path(analysis).name}"
    return data
