"""The error of ``robot init`` and ``robot check``: bad input, named (exit status 2)."""

from __future__ import annotations


class OnboardingError(ValueError):
    """A model, option or file ``robot init``/``robot check`` cannot use; the message names
    the file, the field or option, the value and the fix; ``field`` is the option or field."""

    def __init__(self, message: str, field: str | None = None) -> None:
        super().__init__(message)
        self.field = field
