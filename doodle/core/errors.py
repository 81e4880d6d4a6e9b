"""The one exception type the CLI turns into a clear one-line message."""


class DoodleError(Exception):
    """Bad input or a failed step, with a message that names the place (file, line, track).

    The CLI prints ``str(error)`` on one line and exits non-zero, without a traceback.
    """


def where(source: str, line: int | None = None, column: str | None = None) -> str:
    """Format a location prefix: ``file:line: column``."""
    place = source
    if line is not None:
        place += f":{line}"
    if column:
        place += f": column {column}"
    return place
