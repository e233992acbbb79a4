"""A launch command's placeholders, filled in so that no file name is ever read as code.

A file may be named ``a;touch PWN;b.osc`` or ``c$(touch PWN)d.osc``. Outside a script such a name is
one argument of the program (no shell sees it). Inside the script of a shell (``sh -c SCRIPT``,
whatever runs the shell: ``timeout 600 sh -c``, ``env sh -c``, ``bash -o pipefail -c``), the name is
never written into the script: each placeholder becomes a reference to an environment variable
(``{SCENARIO}`` -> ``"${SCENARIO}"``), quoted for where it stands (bare, inside "…" or inside '…'),
and the values travel in the child's environment (and as ``NAME=value`` arguments of an ``env`` that
runs the shell, which may clear the environment). A placeholder that stands where no reference can
be made safe (escaped by a backslash, in the code of another interpreter's ``-c``/``-e``, in the
command of a program that hands it to a shell elsewhere) makes the template refused before any job
runs, with the form that is safe: pass the value to the script as an argument (``"$1"``).
"""

from __future__ import annotations

import functools
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass

from executor.batch.errors import BadCommand

SCENARIO = "{SCENARIO}"
OUTPUT_DIR = "{OUTPUT_DIR}"

#: Each placeholder and the environment variable that carries its value into a shell script.
VARIABLES = {SCENARIO: "SCENARIO", OUTPUT_DIR: "OUTPUT_DIR"}

PLACEHOLDER = re.compile(re.escape(SCENARIO) + "|" + re.escape(OUTPUT_DIR))

#: Programs that read a ``-c SCRIPT`` argument as shell code.
SHELLS = frozenset({"sh", "bash", "dash", "zsh", "ksh", "mksh", "ash", "busybox", "yash", "posh"})

#: Interpreters whose ``-c``/``-e`` argument is code of their own language (no placeholder may sit there).
INTERPRETERS = re.compile(r"(python[0-9.]*|perl[0-9.]*|ruby[0-9.]*|node|nodejs|php[0-9.]*|lua[0-9.]*|tclsh)")

#: Programs that hand their command to a shell elsewhere or start it with a fresh environment.
REMOTE_OR_NEW_ENVIRONMENT = frozenset({"ssh", "su", "sudo", "doas", "runuser", "pkexec", "machinectl"})

#: Shell options that take the next argument as their value (``bash -o pipefail -c …``).
OPTIONS_WITH_VALUE = frozenset({"-o", "+o", "-O", "+O", "--rcfile", "--init-file"})

SAFE_FORM = ("pass the values to the script as arguments instead, e.g. "
             "-- sh -c 'scenario_execution \"$1\" -o \"$2\"' sh {SCENARIO} {OUTPUT_DIR}")


@dataclass(frozen=True)
class Launch:
    """One job's argument list and the variables its environment gets (empty without a shell script)."""

    argv: tuple[str, ...]
    environment: tuple[tuple[str, str], ...] = ()


@dataclass(frozen=True)
class Template:
    """A checked launch command: where its shell script is (if any) and that script with references."""

    command: tuple[str, ...]
    script_index: int | None = None      # the argument that is the shell's script
    env_index: int | None = None         # where NAME=value arguments go when ``env`` runs the shell
    script: str = ""                     # the script, its placeholders turned into variable references

    @classmethod
    def of(cls, command: Sequence[str]) -> Template:
        """Check ``command`` and find its shell script; :class:`BadCommand` for an unsafe placeholder."""
        command = tuple(command)
        shell, script_index = _shell_script(command)
        _refuse_unsafe(command, shell, script_index)
        if script_index is None or not PLACEHOLDER.search(command[script_index]):
            return cls(command)
        env_index = shell if any(os.path.basename(a) == "env" for a in command[:shell]) else None
        return cls(command, script_index, env_index, _references(command[script_index]))

    def fill(self, scenario: str, output_dir: str) -> Launch:
        """The argument list of one job, in one pass (a value is never searched for placeholders again)."""
        values = {SCENARIO: scenario, OUTPUT_DIR: output_dir}
        argv = [PLACEHOLDER.sub(lambda m: values[m.group()], arg) for arg in self.command]
        if self.script_index is None:
            return Launch(tuple(argv))
        argv[self.script_index] = self.script
        environment = tuple((VARIABLES[p], values[p]) for p in (SCENARIO, OUTPUT_DIR))
        if self.env_index is not None:
            argv[self.env_index:self.env_index] = [f"{name}={value}" for name, value in environment]
        return Launch(tuple(argv), environment)


def substitute(command: Sequence[str], scenario: str, output_dir: str) -> Launch:
    """``Template.of(command).fill(scenario, output_dir)``: one job's arguments and environment (a batch's
    command is checked once, not once per job)."""
    return _template(tuple(command)).fill(scenario, output_dir)


@functools.lru_cache(maxsize=16)
def _template(command: tuple[str, ...]) -> Template:
    return Template.of(command)


def _shell_script(command: tuple[str, ...]) -> tuple[int, int | None]:
    """(where the shell program stands, where its ``-c`` script stands) of the first shell with a script."""
    for position, arg in enumerate(command):
        name = os.path.basename(arg)
        if name not in SHELLS:
            continue
        start = position + 1
        if name == "busybox":
            if start >= len(command) or command[start] not in SHELLS:
                continue
            start += 1
        script = _script_after_options(command, start)
        if script is not None:
            return position, script
    return len(command), None


def _script_after_options(command: tuple[str, ...], start: int) -> int | None:
    position = start
    while position < len(command):
        arg = command[position]
        if arg == "--" or not arg.startswith(("-", "+")):
            return None
        if arg in OPTIONS_WITH_VALUE:
            position += 2
            continue
        if not arg.startswith("--") and "c" in arg[1:]:
            return position + 1 if position + 1 < len(command) else None
        position += 1
    return None


def _refuse_unsafe(command: tuple[str, ...], shell: int, script_index: int | None) -> None:
    """Refuse placeholders that would be code of another interpreter, or cross a remote or fresh environment."""
    for position, arg in enumerate(command):
        name = os.path.basename(arg)
        if INTERPRETERS.fullmatch(name) and position < shell:
            code = position + 1
            while code + 1 < len(command) and command[code].startswith("-"):
                if command[code] in ("-c", "-e", "-E") and PLACEHOLDER.search(command[code + 1]):
                    raise BadCommand(f"{name}: a placeholder inside the code of {command[code]} would run a file "
                                     f"name as {name} code; pass it as an argument (sys.argv[1]) instead")
                code += 1
        if name in REMOTE_OR_NEW_ENVIRONMENT and position < shell:
            later = command[position + 1:]
            if name == "ssh" and any(PLACEHOLDER.search(a) for a in later):
                raise BadCommand("ssh hands its command to a shell on the other host, which would read the "
                                 "file name as code; run the batch on that host (scenario_batch_execution worker)")
            if script_index is not None and PLACEHOLDER.search(command[script_index]):
                raise BadCommand(f"{name} starts the shell with a new environment, so a placeholder inside its "
                                 f"script cannot be passed safely; {SAFE_FORM}")


def _references(script: str) -> str:
    """``script`` with each placeholder replaced by a variable reference quoted for where it stands."""
    pieces: list[str] = []
    last = 0
    for match in PLACEHOLDER.finditer(script):
        context = _context_at(script, match.start())
        if context == "escaped":
            raise BadCommand(f"a backslash escapes the placeholder {match.group()} in the shell script; "
                             f"remove it ({SAFE_FORM})")
        name = VARIABLES[match.group()]
        reference = {"D": f"${{{name}}}", "S": f"'\"${{{name}}}\"'", "E": f"'\"${{{name}}}\"$'"}.get(
            context, f"\"${{{name}}}\"")
        pieces += [script[last:match.start()], reference]
        last = match.end()
    pieces.append(script[last:])
    return "".join(pieces)


def _context_at(script: str, end: int) -> str:
    """The quoting in force at ``script[end]``: U bare, D "…", S '…', E $'…', B `…`, P $(…), or escaped.

    A small scanner of POSIX quoting (nested command substitutions included); comments and here-documents
    are read as bare text, where a reference is harmless.
    """
    stack = ["U"]
    position = 0
    while position < end:
        char, top = script[position], stack[-1]
        step = 1
        if top == "S":
            if char == "'":
                stack.pop()
        elif char == "\\" and top != "S":
            if position + 1 == end:
                return "escaped"
            step = 2
        elif top == "E":
            if char == "'":
                stack.pop()
        elif top == "D":
            if char == '"':
                stack.pop()
            elif script.startswith("$(", position):
                stack.append("P")
                step = 2
            elif char == "`":
                stack.append("B")
        else:
            step = _bare(script, position, stack)
        position += step
    return stack[-1]


def _bare(script: str, position: int, stack: list[str]) -> int:
    """One step of the scanner outside quotes (or inside ``$(…)`` or backquotes); returns its length."""
    char, top = script[position], stack[-1]
    if script.startswith("$'", position):
        stack.append("E")
        return 2
    if script.startswith("$(", position):
        stack.append("P")
        return 2
    if char == "'":
        stack.append("S")
    elif char == '"':
        stack.append("D")
    elif char == "`":
        if top == "B":
            stack.pop()
        else:
            stack.append("B")
    elif char == "(" and top == "P":
        stack.append("P")
    elif char == ")" and top == "P":
        stack.pop()
    return 1
