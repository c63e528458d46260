"""Type stubs of the texwarp package: the extension's functions and classes, and texwarp.errors' exceptions."""

from ._texwarp import Client as Client
from ._texwarp import Job as Job
from ._texwarp import __version__ as __version__
from ._texwarp import map_points as map_points
from ._texwarp import run_local as run_local
from ._texwarp import submit_local as submit_local
from ._texwarp import warp as warp
from .errors import Error as Error
from .errors import InputError as InputError
from .errors import JobCanceledError as JobCanceledError
from .errors import JobFailedError as JobFailedError
from .errors import ProblemError as ProblemError

__all__ = ["Client", "Job", "run_local", "submit_local", "warp", "map_points", "Error", "ProblemError", "InputError",
           "JobFailedError", "JobCanceledError", "__version__"]
