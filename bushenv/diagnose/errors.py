"""The diagnosis's error: records or options that cannot be diagnosed as given."""

from bushenv.errors import BadInput


class DiagnoseError(BadInput):
    """The records cannot be diagnosed as given; the message names the record and the reason."""
