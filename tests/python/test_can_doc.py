"""docs/can.md's "Messages and signals" section is what `fluxdrive can doc`
prints from the DBC (the DBC is the one source of the protocol)."""

from __future__ import annotations

from pathlib import Path

from fluxdrive.can.protocol import message_table_markdown

DOC = Path(__file__).resolve().parents[2] / "docs" / "can.md"


def test_can_md_tables_are_the_dbcs():
    text = DOC.read_text()
    start = text.index("(regenerate this section\nafter editing the DBC):\n\n")
    start = text.index("\n\n", start) + 2
    end = text.index("\n## Connecting with python-can")
    assert text[start:end].rstrip() == message_table_markdown().rstrip(), \
        "run: fluxdrive can doc, and paste it into docs/can.md"
