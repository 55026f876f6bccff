"""The one error of the map tools: names the file, the check and the place."""

from __future__ import annotations


class FluxMapError(Exception):
    """A map refused: ``file: check: where: detail`` (``FluxMapError(file,
    check, detail)`` or ``FluxMapError(file, check, where, detail)``)."""

    def __init__(self, file: str, check: str, where_or_detail: str, detail: str | None = None):
        where, det = (where_or_detail, detail) if detail is not None else ("", where_or_detail)
        self.file, self.check, self.where, self.detail = str(file), check, where, det
        super().__init__(f"{self.file}: {check}: " + (f"{where}: " if where else "") + det)
