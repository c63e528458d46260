"""texwarp's exceptions: a problem (RFC 9457) from texwarpd or from a local run, and a job's input found wrong."""


class Error(Exception):
    """Every error the texwarp module raises (besides TypeError for arguments of the wrong Python type)."""


class ProblemError(Error):
    """A problem: type (a URN "urn:texwarp:problem:<slug>"), path (the JSON path of the offending value, "" when
    none), detail (what went wrong, what to fix), status (the HTTP status; 0 when no server answered), title."""

    def __init__(self, type: str, path: str, detail: str, status: int = 0, title: str = "") -> None:
        self.type = type
        self.path = path
        self.detail = detail
        self.status = status
        self.title = title
        super().__init__(f"{path}: {detail}" if path else detail)


class InputError(ProblemError):
    """A job that is wrong, found here before or while it ran in-process (run_local / submit_local): path names
    the value ("$.mesh.features.features[3].target")."""

    def __init__(self, path: str, detail: str, type: str = "urn:texwarp:problem:invalid-job", status: int = 0,
                 title: str = "Invalid job") -> None:
        super().__init__(type, path, detail, status, title)


class JobFailedError(ProblemError):
    """The job ran and failed: the job's error problem."""


class JobCanceledError(Error):
    """The job was canceled before it finished."""
