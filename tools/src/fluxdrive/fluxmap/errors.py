"""The one error of the map tools: names the file, the check and the place."""

from __future__ import annotations


class FluxMapError(Exception):
    """A map refused: ``file: check: where: detail``."""

    def __init__(self, file: str, check: str, detail: str, where: str = ""):
        self.file, self.check, self.where, self.detail = str(file), check, where, detail
        super().__init__(f"{self.file}: {check}: " + (f"{where}: " if where else "") + detail)
