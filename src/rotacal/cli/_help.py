"""Help-text pieces every command shares: the example block at the end of ``--help``."""

from __future__ import annotations

#: Widest example line (click indents the block by two spaces in an 80-column terminal).
_WIDTH = 76


def example(*lines: str) -> str:
    """A click epilog showing ``lines`` as typed: click's ``\\b`` keeps them from being re-wrapped.

    Each line is one shell command (or one with a ``# comment`` after it); a command wider than
    the terminal is broken before one of its options with a shell continuation (`` \\``). The
    block is headed "Example:" or "Examples:".
    """
    title = "Example:" if len(lines) == 1 else "Examples:"
    shown = [part for line in lines for part in _continued(line)]
    return "\b\n" + title + "\n" + "\n".join(f"  {part}" for part in shown)


def _continued(command: str) -> list[str]:
    """``command`` as shell lines of at most _WIDTH characters, broken before ``--`` options."""
    if len(command) <= _WIDTH or "#" in command:
        return [command]
    pieces = command.split(" --")
    lines = [pieces[0]]
    for piece in pieces[1:]:
        if len(lines[-1]) + len(piece) + 3 + 2 > _WIDTH:  # " --" before, " \" after
            lines.append("    --" + piece)
        else:
            lines[-1] += " --" + piece
    return [line + " \\" for line in lines[:-1]] + [lines[-1]]
