"""The one exception type for errors a user can cause (bad file, bad value, unknown key).

The CLI prints ``str(error)`` on one line and exits with code 2; nothing else, no traceback.
Messages name the file or field at fault and what to do about it.
"""


class BayesUpdateError(ValueError):
    """A user error: bad input file, bad value, unknown name.  Message is one line."""

    def __init__(self, message: str):
        super().__init__(" ".join(str(message).split()))
