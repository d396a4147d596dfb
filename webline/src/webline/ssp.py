"""A line as an SSP 1.0 archive: `write_ssp(system, path)` and `read_ssp(path, target_dir) -> System`.

The archive holds SystemStructure.ssd, one parameter set per component (resources/<component>.ssv, bound
to the component, names unprefixed: what libcosim applies) and the FMUs under resources/, one per kind,
carrying each component's profile as resources/<component>.json: an instance reads the file of its own name.
(libcosim unpacks one copy per GUID, so per-component copies of an FMU would share the first one's resources.)
The step is the DefaultExperiment's OSP annotation (osp:FixedStepAlgorithm baseStepSize), which libcosim reads and `ssp_step` reads for others.
Exports set no String or Enumeration variable: FMPy cannot set them and libcosim ignores Enumerations.
An archive read is untrusted input (archive.py); every error names the file and the entry.
"""

from __future__ import annotations

import json
import math
import tempfile
import zipfile
from pathlib import Path

from lxml import etree

from .archive import ArchiveError, check_archive, extract
from .system import Component, Connection, System, fmu_with_profiles

NS = {
    "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
    "ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
    "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
    "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations",
    "wl": "https://github.com/ConvertingSpan/webline",
}
OSP = "com.opensimulationplatform"
WEBLINE = "com.convertingspan.webline"  # our annotation: the recorded variables
SSD = "SystemStructure.ssd"
FMU_TYPE = "application/x-fmu-sharedlibrary"
KINDS = {"ConvertingSpan": "span", "Roller": "roller"}  # modelName -> System kind
PROFILE = "resources/profile.json"  # an instance's profile when the FMU holds no resources/<instance>.json
PROFILE_BYTES = 16 << 20
XML_PARSER = etree.XMLParser(resolve_entities=False, no_network=True, huge_tree=False, remove_comments=True)


class SspError(ValueError):
    """An SSP archive that cannot be written or read; the message names the file and the entry."""


def _q(prefix: str, tag: str) -> str:
    return f"{{{NS[prefix]}}}{tag}"


def _schema(name: str) -> etree.XMLSchema:
    import fmpy.ssp

    return etree.XMLSchema(file=str(Path(fmpy.ssp.__file__).parent / "schema" / name))


def validate(root, schema: str, where: str):
    """Refuses an XML tree that FMPy's SSP 1.0 schema `schema` rejects, with the schema's first errors."""
    s = _schema(schema)
    if not s.validate(root):
        errors = "; ".join(f"line {e.line}: {e.message}" for e in list(s.error_log)[:3])
        raise SspError(f"{where}: not valid SSP 1.0 ({schema}): {errors}")


def _variables(fmu: Path) -> tuple[str, dict]:
    from fmpy import read_model_description

    try:
        md = read_model_description(str(fmu), validate=False)
    except Exception as e:  # FMPy raises plain Exceptions for a broken model description
        raise SspError(f"{fmu}: no readable modelDescription.xml ({e})") from None
    return md.modelName, {v.name: v for v in md.modelVariables}


# ---------------------------------------------------------------- writing

def _literal(where: str, var, value) -> tuple[str, str]:
    """The .ssv element and value text of a start value, or SspError for what FMPy or libcosim cannot set."""
    t = var.type
    if t == "Real":
        x = float(value)
        if not math.isfinite(x):
            raise SspError(f"{where}: {x} is not a finite Real")
        return "Real", repr(x)
    if t == "Integer":
        if isinstance(value, bool) or int(value) != value:
            raise SspError(f"{where}: {value!r} is not an Integer")
        return "Integer", str(int(value))
    if t == "Boolean":
        if not isinstance(value, (bool, int)) or value not in (0, 1):
            raise SspError(f"{where}: {value!r} is not a Boolean")
        return "Boolean", "true" if value else "false"
    raise SspError(f"{where}: a {t} variable: FMPy's SSP simulation cannot set String or Enumeration variables and "
                   f"libcosim ignores Enumerations; give a profile as the component's profile "
                   f"(resources/<component>.json of its FMU), other choices as Integer or Boolean parameters")


def E(prefix: str, tag: str, parent=None, **attrs):
    """An element of namespace `prefix` (the root declares every prefix: libcosim reads them literally)."""
    attrs = {k: str(v) for k, v in attrs.items()}
    if parent is None:
        return etree.Element(_q(prefix, tag), attrs, nsmap=NS)
    return etree.SubElement(parent, _q(prefix, tag), attrs)


def ssd_tree(system: System, sources: dict, variables: dict) -> etree._Element:
    """SystemStructure.ssd of a system; `sources`: component -> FMU path in the archive,
    `variables`: component -> {name: FMPy ScalarVariable}."""
    root = E("ssd", "SystemStructureDescription", version="1.0", name=system.name, generationTool="webline")
    sys_el = E("ssd", "System", root, name=system.name)
    elements = E("ssd", "Elements", sys_el)
    inputs = {c.target for c in system.connections}
    outputs = {c.source for c in system.connections} | set(system.record)
    for comp in system.components:
        el = E("ssd", "Component", elements, name=comp.name, type=FMU_TYPE, source=sources[comp.name])
        conns = E("ssd", "Connectors", el)
        vars_ = variables[comp.name]
        # FMPy's SSP simulation needs every input connector connected: unconnected inputs are parameters here.
        for name, v in vars_.items():
            if (comp.name, name) in inputs:
                kind = "input"
            elif (comp.name, name) in outputs:
                kind = "output"
            else:
                continue
            c = E("ssd", "Connector", conns, name=name, kind=kind)
            if v.type not in ("Real", "Integer", "Boolean"):
                raise SspError(f"{system.name}: {comp.name}.{name}: a {v.type} connector (FMPy and libcosim "
                               f"connect Real, Integer and Boolean variables)")
            E("ssc", v.type, c)
        binding = E("ssd", "ParameterBindings", el)
        E("ssd", "ParameterBinding", binding, source=f"resources/{comp.name}.ssv")
    connections = E("ssd", "Connections", sys_el)
    for c in system.connections:
        E("ssd", "Connection", connections, startElement=c.source[0], startConnector=c.source[1],
          endElement=c.target[0], endConnector=c.target[1])
    annotations = E("ssd", "Annotations", sys_el)
    a = E("ssc", "Annotation", annotations, type=WEBLINE)
    rec = E("wl", "Record", a)
    for comp, var in system.record:
        E("wl", "Variable", rec, component=comp, name=var)
    for name, terms in system.sums or []:  # a column made of several (a laminate's, of its layers' spans)
        col = E("wl", "Column", rec, name=name)
        for i, w in terms:
            E("wl", "Term", col, variable=str(i), weight=repr(float(w)))
    exp = E("ssd", "DefaultExperiment", root, startTime=repr(float(system.start_time)), stopTime=repr(float(system.stop_time)))
    a = E("ssc", "Annotation", E("ssd", "Annotations", exp), type=OSP)
    E("osp", "FixedStepAlgorithm", E("osp", "Algorithm", a), baseStepSize=repr(float(system.step)))
    return root


def ssv_tree(comp: Component, variables: dict, where: str) -> etree._Element:
    root = etree.Element(_q("ssv", "ParameterSet"), version="1.0", name=comp.name,
                         nsmap={"ssv": NS["ssv"], "ssc": NS["ssc"]})
    params = etree.SubElement(root, _q("ssv", "Parameters"))
    for name, value in comp.start.items():
        v = variables.get(name)
        w = f"{where}: {comp.name}.{name}"
        if v is None:
            raise SspError(f"{w}: no such variable in {Path(comp.fmu).name}")
        if v.causality not in ("parameter", "input"):
            raise SspError(f"{w}: a start value for a variable of causality {v.causality} (libcosim sets parameters and inputs only)")
        kind, text = _literal(w, v, value)
        p = etree.SubElement(params, _q("ssv", "Parameter"), name=name)
        etree.SubElement(p, _q("ssv", kind), value=text)
    return root


def write_ssp(system: System, path) -> Path:
    """Writes `system` as an SSP 1.0 archive at `path`: valid against FMPy's SSP schemas, runnable unchanged
    by libcosim and (with its parameter sets passed, see engines.run_fmpy) by FMPy."""
    path = Path(path)
    names = [c.name for c in system.components]
    if len(set(names)) != len(names):
        raise SspError(f"{system.name}: two components share a name")

    if not (system.step > 0 and system.stop_time > system.start_time):
        raise SspError(f"{system.name}: step {system.step} and times {system.start_time}..{system.stop_time} are not an experiment")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        files, sources, variables = {}, {}, {}
        for comp in system.components:
            fmu = Path(comp.fmu)
            if not fmu.is_file():
                raise SspError(f"{system.name}: {comp.name}: FMU {fmu} is missing")
            _, variables[comp.name] = _variables(fmu)
        for fmu in dict.fromkeys(Path(c.fmu) for c in system.components):
            users = [c for c in system.components if Path(c.fmu) == fmu]
            profiles = {f"{c.name}.json": c.profile for c in users if c.profile is not None}
            if profiles:  # a part without one gets an empty one, its own: it carries no drive, and knows it
                profiles.update({f"{c.name}.json": {} for c in users if c.profile is None})
            name = f"resources/{fmu.name}"
            while name in files:
                name = name[:-4] + "_.fmu"
            files[name] = fmu_with_profiles(fmu, profiles, tmp) if profiles else fmu
            for c in users:
                sources[c.name] = name
        for c in system.connections:
            for end, causality in ((c.source, "output"), (c.target, "input")):
                v = variables.get(end[0], {}).get(end[1])
                if v is None or v.causality != causality:
                    raise SspError(f"{system.name}: connection {c.source[0]}.{c.source[1]} -> {c.target[0]}.{c.target[1]}: "
                                   f"{end[0]}.{end[1]} is not an {causality} of a component")
        ssd = ssd_tree(system, sources, variables)
        validate(ssd, "SystemStructureDescription.xsd", f"{path}: {SSD}")
        ssvs = {}
        for comp in system.components:
            ssv = ssv_tree(comp, variables[comp.name], str(path))
            validate(ssv, "SystemStructureParameterValues.xsd", f"{path}: resources/{comp.name}.ssv")
            ssvs[f"resources/{comp.name}.ssv"] = ssv
        path.parent.mkdir(parents=True, exist_ok=True)
        partial = path.with_name(path.name + ".part")
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as zf:
            zf.writestr(SSD, etree.tostring(ssd, xml_declaration=True, encoding="UTF-8", pretty_print=True))
            for name, tree in ssvs.items():
                zf.writestr(name, etree.tostring(tree, xml_declaration=True, encoding="UTF-8", pretty_print=True))
            for name, f in files.items():
                zf.write(f, name)
        partial.replace(path)
    return path


# ---------------------------------------------------------------- reading

def _parse(path: Path, where: str):
    try:
        tree = etree.parse(str(path), XML_PARSER)
    except (etree.XMLSyntaxError, OSError) as e:
        raise SspError(f"{where}: not readable XML ({e})") from None
    if tree.docinfo.internalDTD is not None or tree.docinfo.doctype:
        raise SspError(f"{where}: a DOCTYPE declaration (SSP files have none; entities are not expanded)")
    return tree.getroot()


def ssp_step(root) -> float | None:
    """The step of an SSD tree: the OSP annotation libcosim reads (what FMPy callers pass as step_size)."""
    alg = root.find("ssd:DefaultExperiment/ssd:Annotations/ssc:Annotation/osp:Algorithm/osp:FixedStepAlgorithm", NS)
    return None if alg is None else float(alg.get("baseStepSize"))


def _inside(root: Path, rel: str, where: str) -> Path:
    """A file named by the archive (an FMU, a parameter set): a relative path to a regular file inside `root`."""
    if not rel or rel.startswith(("/", "\\")) or ":" in rel or ".." in Path(rel).parts:
        raise SspError(f"{where}: {rel!r} is not a relative path inside the archive")
    p = root / rel
    if p.is_symlink() or not p.is_file() or root not in p.resolve().parents:
        raise SspError(f"{where}: {rel!r} is missing from the archive")
    return p


def _value(text: str, kind: str, where: str):
    try:
        if kind == "Real":
            return float(text)
        if kind == "Integer":
            return int(text)
        if kind == "Boolean":
            return {"true": True, "false": False, "1": True, "0": False}[text.strip()]
        if kind == "String":
            return text
    except (ValueError, KeyError):
        raise SspError(f"{where}: {text!r} is not a {kind}") from None
    raise SspError(f"{where}: a {kind} value (webline sets Real, Integer, Boolean and String variables)")


def _start_values(root: Path, el, variables: dict, where: str) -> dict:
    start = {}
    for b in el.findall("ssd:ParameterBindings/ssd:ParameterBinding", NS):
        prefix = b.get("prefix", "")
        if b.get("source") is not None:
            rel = b.get("source")
            w = f"{where}: {rel}"
            sets = [_parse(_inside(root, rel, where), w)]
            validate(sets[0], "SystemStructureParameterValues.xsd", w)
        else:
            w = where
            sets = b.findall("ssd:ParameterValues/ssv:ParameterSet", NS)
        if b.find("ssd:ParameterMapping", NS) is not None:
            raise SspError(f"{where}: a parameter mapping (webline reads parameter sets without mappings)")
        for ps in sets:
            for p in ps.findall("ssv:Parameters/ssv:Parameter", NS):
                name = p.get("name")
                if prefix and name.startswith(prefix):
                    name = name[len(prefix):]
                if name not in variables:
                    raise SspError(f"{w}: parameter {name!r}: no such variable in the component's FMU")
                value = p[0]
                start[name] = _value(value.get("value", ""), etree.QName(value).localname, f"{w}: parameter {name!r}")
    return start


def read_ssp(path, target_dir) -> System:
    """Reads an SSP archive (ours or a user's with our FMUs) into a System, extracting it into `target_dir`
    (new or empty) as untrusted input; the System's FMUs are the extracted files."""
    path = Path(path)
    try:
        root = extract(path, Path(target_dir))
        for fmu in root.rglob("*.fmu"):
            check_archive(fmu)
    except ArchiveError as e:
        raise SspError(str(e)) from None
    ssd_path = root / SSD
    if not ssd_path.is_file() or ssd_path.is_symlink():
        raise SspError(f"{path}: entry {SSD!r} is missing")
    where = f"{path}: {SSD}"
    ssd = _parse(ssd_path, where)
    validate(ssd, "SystemStructureDescription.xsd", where)
    exp = ssd.find("ssd:DefaultExperiment", NS)
    if exp is None or exp.get("stopTime") is None:
        raise SspError(f"{where}: no ssd:DefaultExperiment with a stopTime")
    step = ssp_step(ssd)
    if step is None or not step > 0:
        raise SspError(f"{where}: no positive step (ssd:DefaultExperiment annotation {OSP}: "
                       f"osp:Algorithm/osp:FixedStepAlgorithm baseStepSize)")
    sys_el = ssd.find("ssd:System", NS)
    if sys_el.find("ssd:Elements/ssd:System", NS) is not None:
        raise SspError(f"{where}: a nested system (webline reads flat systems of components)")
    components, variables = [], {}
    for el in sys_el.findall("ssd:Elements/ssd:Component", NS):
        name = el.get("name")
        w = f"{where}: component {name!r}"
        if el.get("type", FMU_TYPE) != FMU_TYPE:
            raise SspError(f"{w}: of type {el.get('type')!r} (webline runs FMUs)")
        fmu = _inside(root, el.get("source"), w)
        model, variables[name] = _variables(fmu)
        if model not in KINDS:
            raise SspError(f"{w}: {el.get('source')} is a {model!r}, not one of this project's FMUs ({', '.join(KINDS)})")
        profile = None
        with zipfile.ZipFile(fmu) as zf:
            own = next((f for f in (f"resources/{name}.json", PROFILE) if f in zf.namelist()), None)
            if own is not None:
                if zf.getinfo(own).file_size > PROFILE_BYTES:
                    raise SspError(f"{w}: {el.get('source')}: {own} is larger than {PROFILE_BYTES} bytes")
                try:
                    # An empty one is a part's without a drive (written so that it finds its own file).
                    profile = json.loads(zf.read(own)) or None
                except ValueError as e:
                    raise SspError(f"{w}: {el.get('source')}: {own} is not JSON ({e})") from None
        components.append(Component(name=name, kind=KINDS[model], fmu=fmu,
                                    start=_start_values(root, el, variables[name], w), profile=profile))
    if not components:
        raise SspError(f"{where}: no components")
    connections = []
    for c in sys_el.findall("ssd:Connections/ssd:Connection", NS):
        ends = (c.get("startElement"), c.get("startConnector")), (c.get("endElement"), c.get("endConnector"))
        for end, causality in zip(ends, ("output", "input")):
            v = variables.get(end[0], {}).get(end[1])
            if v is None or v.causality != causality:
                raise SspError(f"{where}: connection {ends[0][0]}.{ends[0][1]} -> {ends[1][0]}.{ends[1][1]}: "
                               f"{end[0]}.{end[1]} is not an {causality} of a component")
        if c.find("ssc:*", NS) is not None:
            raise SspError(f"{where}: connection to {ends[1][0]}.{ends[1][1]}: a transformation (webline connects values as they are)")
        connections.append(Connection(source=ends[0], target=ends[1]))
    rec = sys_el.find(f"ssd:Annotations/ssc:Annotation[@type='{WEBLINE}']/wl:Record", NS)
    sums = None
    if rec is not None:
        record = [(v.get("component"), v.get("name")) for v in rec.findall("wl:Variable", NS)]
        sums = _sums(rec, len(record), where) or None
    else:  # a user's SSP: every output connector
        record = [(el.get("name"), c.get("name")) for el in sys_el.findall("ssd:Elements/ssd:Component", NS)
                  for c in el.findall("ssd:Connectors/ssd:Connector[@kind='output']", NS)]
    for comp, var in record:
        if var not in variables.get(comp, {}):
            raise SspError(f"{where}: recorded variable {comp}.{var} does not exist")
    return System(name=ssd.get("name"), components=components, connections=connections,
                  start_time=float(exp.get("startTime", 0.0)), stop_time=float(exp.get("stopTime")),
                  step=step, record=record, sums=sums)


def _sums(rec, n: int, where: str) -> list:
    """The annotation's columns made of several recorded variables: (name, [(variable index, weight)])."""
    sums = []
    for col in rec.findall("wl:Column", NS):
        name = col.get("name") or ""
        terms = []
        for term in col.findall("wl:Term", NS):
            try:
                i, w = int(term.get("variable", "")), float(term.get("weight", ""))
            except ValueError:
                i, w = -1, math.nan
            if not (0 <= i < n and math.isfinite(w)):
                raise SspError(f"{where}: recorded column {name!r}: a term {term.get('variable')!r} x {term.get('weight')!r} "
                               f"(needs a recorded variable's index, 0 to {n - 1}, and a finite weight)")
            terms.append((i, w))
        if not name or not terms:
            raise SspError(f"{where}: a recorded column needs a name and at least one term")
        sums.append((name, terms))
    return sums
