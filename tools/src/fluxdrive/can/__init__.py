"""CAN tools for fluxdrive: the protocol (from the DBC), a Python ``Drive``
API and the ``fluxdrive can ...`` commands (monitor, record, plot, send, doc).
"""

from fluxdrive.can.drive import Drive, DriveError
from fluxdrive.can.protocol import Protocol, load_dbc

__all__ = ["Drive", "DriveError", "Protocol", "load_dbc"]
