"""Errors the CLI reports as one clear line (no traceback)."""

from __future__ import annotations

#: Exit code for a user error (bad path, bad argument, unknown signal...).
EXIT_USAGE = 2


class FluxdriveError(Exception):
    """An error caused by user input or environment; printed without traceback."""

    def __init__(self, message: str, exit_code: int = EXIT_USAGE, hint: str | None = None):
        super().__init__(message)
        self.message = message
        self.exit_code = exit_code
        self.hint = hint

    def __str__(self) -> str:  # pragma: no cover - trivial
        if self.hint:
            return f"{self.message}\nhint: {self.hint}"
        return self.message
