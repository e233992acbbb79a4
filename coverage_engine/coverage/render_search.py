"""The ``Search`` section of the text and JSON reports: the rounds of a search and its latest estimate.

Short on purpose (it is what CI prints in a pipe): one line for the search, one per round, then the
estimate in the words the search itself printed at its end (:func:`coverage_engine.search_record.estimate_lines`).
"""

from __future__ import annotations

from typing import Any

from coverage_engine.coverage.search_rounds import SearchSection
from coverage_engine.printable import printable
from coverage_engine.search_record import estimate_dict, estimate_lines


def search_head(section: SearchSection) -> str:
    """``Search: goal boundary, 40 of 40 run(s) in 3 round(s)``."""
    runs = sum(r.runs for r in section.rounds)
    goal = f"goal {section.goal}, " if section.goal else ""
    budget = f" of {section.budget}" if section.budget is not None else ""
    return f"Search: {goal}{runs}{budget} run(s) in {len(section.rounds)} round(s)"


def search_lines(section: SearchSection) -> list[str]:
    """The section as plain lines (no blank line inside: the report's sections are split at blank lines)."""
    width = max([len(r.strategy) for r in section.rounds] + [len("strategy")])
    lines = [printable(search_head(section)),
             f"  round  {'strategy':<{width}}  runs  passed  not passed"]
    for r in section.rounds:
        lines.append(f"  {r.round:>5}  {printable(r.strategy):<{width}}  {r.runs:>4}  {r.passed:>6}  {r.not_passed:>10}")
    lines.append(f"  estimate of round {section.latest_round}:")
    lines.extend(f"    {printable(line)}" for line in estimate_lines(section.estimate))
    return lines


def search_dict(section: SearchSection) -> dict[str, Any]:
    """The ``search`` object of the JSON report (see docs/search.md)."""
    return {
        "goal": section.goal, "budget": section.budget, "latest_round": section.latest_round,
        "rounds": [{"round": r.round, "strategy": r.strategy, "runs": r.runs, "passed": r.passed,
                    "not_passed": r.not_passed} for r in section.rounds],
        "estimate": estimate_dict(section.estimate),
        "runs": [{"name": name, "round": number} for name, number in section.run_rounds],
    }


def search_html(section: SearchSection) -> str:
    """The ``Search`` section of the HTML page: the rounds, the estimate, and the runs by round drawn
    over two ranges with the boundary and the worst case."""
    from html import escape

    from coverage_engine.coverage.render_svg import round_colour, search_svg

    rows = "".join(f'<tr><td><span class="dot" style="background:{round_colour(r.round)}"></span> {r.round}</td>'
                   f'<td>{escape(r.strategy)}</td><td class="num">{r.runs}</td><td class="num">{r.passed}</td>'
                   f'<td class="num">{r.not_passed}</td></tr>' for r in section.rounds)
    estimate = "".join(f'<li class="sub">{escape(line.strip())}</li>' if line.startswith(" ") else
                       f"<li>{escape(line)}</li>" for line in estimate_lines(section.estimate))
    picture = search_svg(section) or ""
    return (f'<section class="group" id="search"><h2>{escape(search_head(section))}</h2>'
            '<p class="lead">Each round ran the variants its strategy proposed from the results of the rounds '
            'before it.</p><table class="rounds"><thead><tr><th>round</th><th>strategy</th><th>runs</th>'
            f'<th>passed</th><th>not passed</th></tr></thead><tbody>{rows}</tbody></table>'
            f'<h3>Estimate of round {section.latest_round}</h3><ul class="estimate">{estimate}</ul>'
            f'{picture}</section>')
