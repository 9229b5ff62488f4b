"""The diagnosis's error: records or options that cannot be diagnosed as given."""


class DiagnoseError(ValueError):
    """The records cannot be diagnosed as given; the message names the record and the reason."""
