"""The rooms' one-way dependencies (docs/design.md, "Layout"): every `use` of a module of src/ in
src/**/*.f90 points to a module of an earlier room, or of the same room; rooms named together in
parentheses (`fluid`, `particles`) never use each other; the main program (src/agglo.f90) comes
last. The room order is read from the dependency line of docs/design.md
("`core` -> `config` -> ... -> main program."), so the page and the code cannot drift apart.

Usage: python3 check_rooms.py REPOSITORY
Prints one line per backward use ("room/module uses room/module") and per folder of src/ that the
line does not name; exit status 0 when there is none, 1 otherwise, 2 when the line is missing.
Standard library only."""
import re
import sys
from pathlib import Path

USE = re.compile(r"^\s*use\b(?!.*\bintrinsic\b)\s*(?:,\s*non_intrinsic\s*)?(?:::)?\s*(\w+)", re.I)
MODULE = re.compile(r"^\s*module\s+(\w+)\s*(?:!.*)?$", re.I)


def room_order(design):
    """{room: level} from the line "`core` -> `config` -> ... -> main program." of design.md; rooms
    in one parenthesised group share a level. None when the page has no such line."""
    for line in design.splitlines():
        if line.startswith("`core` ->") and "main program" in line:
            levels = {}
            for level, stage in enumerate(line.split("->")):
                for room in re.findall(r"`(\w+)`", stage):
                    levels[room] = level
                if "main program" in stage:
                    levels["main program"] = level
            return levels
    return None


def violations(repo):
    repo = Path(repo)
    levels = room_order((repo / "docs" / "design.md").read_text())
    if levels is None:
        return None
    src = repo / "src"
    owner, uses, problems = {}, {}, []
    for path in sorted(src.rglob("*.f90")):
        relative = path.relative_to(src)
        room = relative.parts[0] if len(relative.parts) > 1 else "main program"
        if room not in levels:
            problems.append(f"src/{relative}: room '{room}' is not in docs/design.md's dependency line")
            continue
        for line in path.read_text(errors="replace").splitlines():
            code = line.split("!", 1)[0]
            module = MODULE.match(code)
            if module and module.group(1).lower() != "procedure":
                owner[module.group(1).lower()] = room
            used = USE.match(code)
            if used:
                uses.setdefault((room, path.stem), set()).add(used.group(1).lower())
    for (room, name), used in sorted(uses.items()):
        for module in sorted(used):
            if module not in owner:
                continue   # intrinsic or external (mpi_f08, hdf5, fftw)
            other = owner[module]
            if levels[other] > levels[room] or (levels[other] == levels[room] and other != room):
                problems.append(f"{room}/{name} uses {other}/{module}")
    return problems


def main(argv):
    problems = violations(argv[1] if len(argv) > 1 else ".")
    if problems is None:
        print("no dependency line (`core` -> ... -> main program.) in docs/design.md")
        return 2
    for problem in problems:
        print(problem)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
