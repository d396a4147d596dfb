"""One set of names: the engines that run a line, and the columns every engine writes.

Every engine's CSV names its columns as the scene records them, "part.quantity [unit]" ("film.T [N]",
"idler.v [m/s]"). A scene's quantity is one variable of the part's FMU (SPAN_VARIABLES, ROLLER_VARIABLES);
a System's recorded variables are named back by `scene_columns`, an SSP archive's too.
"""

from __future__ import annotations

from .scene import LAYON_QUANTITIES, LOAD_CELL_QUANTITIES, QUANTITIES, TRACTION_QUANTITIES

# The engines (engines.py runs them): the Line FMU, the reference, webline's co-simulation of the parts,
# and an SSP archive in libcosim or FMPy.
ENGINES = ("line", "reference", "parts", "libcosim", "fmpy")
ALIASES = {"fmpy-line": "line"}
DEFAULT = "line"
ARCHIVE_ENGINES = ("parts", "libcosim", "fmpy")  # what runs an SSP archive (parts by default)

# A scene's recorded quantity -> the FMU variable that holds it.
SPAN_VARIABLES = {"T": "summary_Tension", "eps": "summary_Strain", "L": "summary_Length", "F_a": "web_a.F", "F_b": "web_b.F"}
ROLLER_VARIABLES = {"v": "v", "omega": "omega", "tau": "tau", "r": "r", "y": "y", "y_dot": "y_dot", "eps": "web_b.eps",
                    "v_web": "v_web", "slip": "slip", "traction": "traction", "mu_eff": "mu_eff", "h_air": "h_air",
                    "F": "load_cell.F", **{q: q for q in LAYON_QUANTITIES}}


def engine_name(text: str) -> str:
    """An engine's name, its old alias resolved; ValueError for another name."""
    name = ALIASES.get(text, text)
    if name not in ENGINES:
        raise ValueError(f"unknown engine {text!r} (engines: {', '.join(ENGINES)})")
    return name


def scene_quantity(kind: str, variable: str):
    """(quantity, unit) a scene records as `variable` of a component of `kind` ("span", "roller"),
    or None: the inverse of SPAN_VARIABLES and ROLLER_VARIABLES, a roller's speed at either port."""
    if kind == "span":
        names = {v: q for q, v in SPAN_VARIABLES.items()}
        units = QUANTITIES["span"]
    else:
        names = {**{v: q for q, v in ROLLER_VARIABLES.items()}, "web_a.v": "v", "web_b.v": "v"}
        units = {**QUANTITIES["dancer"], **QUANTITIES["winder"], **QUANTITIES["source"], **TRACTION_QUANTITIES,
                 **LOAD_CELL_QUANTITIES, **LAYON_QUANTITIES}
    q = names.get(variable)
    return (q, units[q]) if q is not None else None


def scene_columns(system, variables: dict) -> list[str]:
    """A System's recorded variables named as a scene names them (`scene_quantity`); a variable no
    scene quantity reads keeps its FMU's name. `variables`: each component's {name: FMPy variable}. Columns
    made of several variables (a laminate's, `System.sums`) have their own names."""
    if system.sums is not None:
        return [name for name, _ in system.sums]
    out = []
    for comp, var in system.record:
        named = scene_quantity(system.component(comp).kind, var)
        if named is not None:
            out.append(f"{comp}.{named[0]} [{named[1]}]")
        else:
            v = variables[comp][var]
            out.append(f"{comp}.{var} [{v.unit or getattr(v.declaredType, 'unit', None) or '1'}]")
    return out
