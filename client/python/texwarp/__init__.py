"""texwarp: constrained texture mapping by foldover-free image warping (Seo & Cordier), from Python.

    import texwarp
    result = texwarp.Client("http://127.0.0.1:8080").run(job, "out/")   # on a texwarpd
    result = texwarp.run_local(job, "out/")                              # in this process, no server

Jobs are dicts in the job JSON form (the body of POST /v1/jobs); a result is a dict {"files": [...],
"report": {...}, "job_id": ..., "state": "succeeded"}. Client.submit / submit_local return a Job whose poll(),
state and progress never block (for a DCC's main loop); wait(), cancel(), fetch(out_dir) finish it.
"""

from .errors import Error, InputError, JobCanceledError, JobFailedError, ProblemError
from ._texwarp import Client, Job, run_local, submit_local, __version__

__all__ = ["Client", "Job", "run_local", "submit_local", "Error", "ProblemError", "InputError", "JobFailedError",
           "JobCanceledError", "__version__"]
