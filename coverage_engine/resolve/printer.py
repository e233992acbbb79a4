"""Print a resolved model as an indented tree (``-l/--log-model``)."""

from __future__ import annotations

from coverage_engine.resolve import model


def format_expr(expr: model.Expr) -> str:
    """A short text for a model expression: constants as Python ``repr``, the rest symbolically."""
    if isinstance(expr, model.Const):
        return repr(expr.value)
    if isinstance(expr, model.VariableRef):
        return f"var {expr.variable.key}"
    if isinstance(expr, model.FieldOf):
        return f"{format_expr(expr.target)}.{expr.name}"
    if isinstance(expr, model.ExternalCall):
        args = ", ".join(f"{n}: {format_expr(v)}" for n, v in expr.arguments)
        return f"{expr.method.module}.{expr.method.function}({args})"
    if isinstance(expr, model.Operation):
        parts = [format_expr(o) for o in expr.operands]
        if len(parts) == 1:
            return f"{'-' if expr.op == 'neg' else expr.op + ' '}{parts[0]}"
        return f"({parts[0]} {expr.op} {parts[1]})"
    if isinstance(expr, model.MakeList):
        return "[" + ", ".join(format_expr(i) for i in expr.items) + "]"
    if isinstance(expr, model.MakeStruct):
        return expr.type_name + "(" + ", ".join(f"{n}: {format_expr(v)}" for n, v in expr.members) + ")"
    return repr(expr)


def _behavior_lines(node: model.Behavior, depth: int, out: list[str]) -> None:
    pad = "    " * depth
    if isinstance(node, model.Composite):
        label = f" ({node.name})" if node.name != node.kind else ""
        out.append(f"{pad}{node.kind}{label}")
        for child in node.children:
            _behavior_lines(child, depth + 1, out)
    elif isinstance(node, model.Modified):
        args = ", ".join(f"{n}: {v!r}" for n, v in node.arguments)
        out.append(f"{pad}modifier {node.modifier}({args})")
        _behavior_lines(node.child, depth + 1, out)
    elif isinstance(node, model.ActionCall):
        args = ", ".join(f"{n}: {format_expr(v)}" for n, v in node.arguments)
        label = f" ({node.name})" if node.name != node.action.split(".")[-1] else ""
        out.append(f"{pad}action {node.action}({args}){label}")
    elif isinstance(node, model.WaitElapsed):
        out.append(f"{pad}wait elapsed({format_expr(node.duration)} s)")
    elif isinstance(node, model.WaitCondition):
        out.append(f"{pad}wait {format_expr(node.condition)}")
    elif isinstance(node, model.WaitEvent):
        out.append(f"{pad}wait @{node.event}")
    elif isinstance(node, model.EmitEvent):
        out.append(f"{pad}emit {node.event}")
    elif isinstance(node, model.CallMethod):
        out.append(f"{pad}call {format_expr(node.call)}")


def format_scenario(scenario: model.Scenario) -> str:
    """One scenario: parameters, variables, events and the behaviour tree."""
    out = [f"scenario {scenario.name}"]
    for p in scenario.parameters:
        out.append(f"    parameter {p.name}: {p.type_name} = {p.value!r}")
    for v in scenario.variables:
        out.append(f"    var {v.key}: {v.type_name} = {format_expr(v.initial)}")
    for e in scenario.events:
        out.append(f"    event {e}")
    if scenario.body is not None:
        out.append("    do")
        _behavior_lines(scenario.body, 2, out)
    return "\n".join(out)


def format_model(scenario_file: model.ScenarioFile) -> str:
    """All scenarios of a file, as printed by ``-l``."""
    return "\n".join(format_scenario(s) for s in scenario_file.scenarios)
