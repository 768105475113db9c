"""The interactive page's contract (springlab.render.interactive): the scene in the browser with real MuJoCo
(`Scene.interactive`)."""

from __future__ import annotations

import ast
import dataclasses
from collections.abc import Mapping
from typing import ClassVar


def formula(expression: str, values: Mapping[str, float]) -> float:
    """The value of an `InteractiveSpec` formula: + - * / and parentheses over names and numbers.

    The page evaluates the same text in JavaScript with the same precedence and left-to-right order, so
    both sides round alike (IEEE double arithmetic); names are the scene's parameters and `g` [m/s^2].

    Parameters
    ----------
    expression
        e.g. "clearance + mass * g / stiffness".
    values
        name -> value (SI).
    """

    def walk(node: ast.AST) -> float:
        if isinstance(node, ast.Expression):
            return walk(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)):
            return float(node.value)
        if isinstance(node, ast.Name):
            return float(values[node.id])
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            return -walk(node.operand)
        if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub, ast.Mult, ast.Div)):
            left, right = walk(node.left), walk(node.right)
            op = node.op
            if isinstance(op, ast.Add):
                return left + right
            if isinstance(op, ast.Sub):
                return left - right
            return left * right if isinstance(op, ast.Mult) else left / right
        raise ValueError(f"not a formula of + - * / over names and numbers: {expression!r}")

    return walk(ast.parse(expression, mode="eval"))


@dataclasses.dataclass(frozen=True)
class MjcfEdit:
    """One value written into the MJCF text, the browser's form of a line of `Scene.edit`.

    The page edits the scene's MJCF file as text (an XML attribute) and recompiles it, so the model it
    steps is the one `Scene.build` makes; tests/render/test_interactive.py compiles both and compares them.

    Attributes
    ----------
    value
        what is written: a parameter name or a `formula` over parameters and `g` (e.g. a spring's
        relaxed length from the mass and stiffness), evaluated in the page as they move.
    tag, name
        the element `<tag name="name">` of the MJCF file.
    attribute
        the attribute written (the value in full precision).
    child
        write into this child element of it instead (e.g. a body's `inertial`); None: the element itself.
    """

    value: str
    tag: str
    name: str
    attribute: str
    child: str | None = None


@dataclasses.dataclass(frozen=True)
class InteractiveSpec:
    """A scene whose scenarios run in the browser with real MuJoCo (`springlab interactive`).

    The page's exact solution is the one-mode oscillator m x'' + d x' + k x = F (F constant from t = 0,
    through an actuator's control, as `Scene.setup` holds it), about a rest position (`rest`: a constant
    load such as gravity on a preloaded spring), ported to JavaScript; it is the kind every declaring
    scene shares (`kind`). The sliders move mass, stiffness and the damping ratio (the damping follows).

    Attributes
    ----------
    joint
        the oscillating joint, x; its qpos and qvel are the page's x and v.
    scenarios
        the scenarios the page can run: those whose model is the MJCF with `edits` applied (no
        MjSpec-built parts such as a harmonic exciter); the first is the default.
    edits
        the parameters written into the MJCF text.
    mass, stiffness, damping
        the scene's parameter names of m [kg], k [N/m], d [N s/m].
    x0, v0
        `formula`s of x(0) [m] and v(0) [m/s] as `Scene.setup` computes them.
    force
        `formula` of the constant force F [N] on the joint (None: none).
    actuator
        the actuator whose control holds F.
    rest
        `formula` of the rest position [m] the free motion decays to, where a constant load is
        balanced by a preloaded spring (None: 0); the reference is then rest + the free response from
        x0 - rest, as the scene's.
    ranges
        parameter -> (low, high) of its slider, where it is inside the scene's model (default: a decade
        either side of the scenario's value).
    """

    kind: ClassVar[str] = "oscillator"

    joint: str
    scenarios: tuple[str, ...]
    edits: tuple[MjcfEdit, ...]
    mass: str = "mass"
    stiffness: str = "stiffness"
    damping: str = "damping"
    x0: str = "x0"
    v0: str = "v0"
    force: str | None = None
    actuator: str | None = None
    rest: str | None = None
    ranges: Mapping[str, tuple[float, float]] = dataclasses.field(default_factory=dict)
