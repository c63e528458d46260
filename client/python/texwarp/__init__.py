"""texwarp: constrained texture mapping by foldover-free image warping (Seo & Cordier), from Python.

    import texwarp
    result = texwarp.Client("http://127.0.0.1:8080").run(job, "out/")   # on a texwarpd
    result = texwarp.run_local(job, "out/")                              # in this process, no server
    warped = texwarp.warp(image, {"features": [...]})                    # a NumPy array in, a new one out

Jobs are dicts in the job JSON form (the body of POST /v1/jobs); a result is a dict {"files": [...],
"report": {...}, "job_id": ..., "state": "succeeded"}. Client.submit / submit_local return a Job whose poll(),
state and progress never block (for a DCC's main loop); wait(), cancel(), fetch(out_dir) finish it. warp() and
map_points() work on arrays in memory (an image, N×2 points) with features in the feature-file form, no files.
"""

from .errors import Error, InputError, JobCanceledError, JobFailedError, ProblemError
from ._texwarp import Client, Job, map_points, run_local, submit_local, warp, __version__

__all__ = ["Client", "Job", "run_local", "submit_local", "warp", "map_points", "Error", "ProblemError", "InputError",
           "JobFailedError", "JobCanceledError", "__version__"]
