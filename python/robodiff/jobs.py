"""Batch jobs on robodiffd from Python: the job methods of robodiff.Client.

A job (kind ``"trajectory"``, ``"identify"`` or ``"trajopt"``; its parameters are listed
in schema/README.md) runs in the server's worker processes and writes its files on the
server's host, under its cache's ``jobs/`` folder. The methods mirror the C++ client's
(submitJob, jobs, jobStatus, cancelJob, jobResult) and need a server (shm or dds mode,
or auto with one answering).
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from typing import Any, List, Mapping, Optional, Union

from . import _robodiff
from ._robodiff import JobInfo


@dataclass(frozen=True)
class JobResult:
    """A finished job: its final ``info``, its ``result`` summary (a dict) and ``result_dir``,
    the folder of its files on the server's host."""

    info: JobInfo
    result: Any
    result_dir: str


class JobsMixin:
    """The job methods of robodiff.Client (which holds the C++ client as ``_native``)."""

    _native: Any

    def submit_job(self, kind: str, params: Union[Mapping[str, Any], str]) -> str:
        """Submits a job; returns its id at once (the server runs it in the background).

        params: a dict (sent as JSON) or a JSON object's text. Paths in it are on the
        server's host, inside its ``jobs.data_dirs``. Raises robodiff.Error
        (INVALID_ARGUMENT naming a bad parameter, UNAVAILABLE without a server).
        """
        text = params if isinstance(params, str) else json.dumps(params)
        return _robodiff.submit_job(self._native, kind, text)

    def jobs(self) -> List[JobInfo]:
        """Every job the server knows (queued, running and finished)."""
        return list(_robodiff.jobs(self._native))

    def job_status(self, job_id: str) -> JobInfo:
        """A job's state, progress and latest messages. Raises robodiff.Error (NOT_FOUND)."""
        return _robodiff.job_status(self._native, job_id)

    def cancel_job(self, job_id: str) -> str:
        """Cancels a queued or running job (its files are removed); returns its state after
        the cancel (``"CANCELLED"``, or the final state of a job that had finished)."""
        return _robodiff.cancel_job(self._native, job_id)

    def job_result(self, job_id: str) -> JobResult:
        """A finished job's result. Raises robodiff.Error (FAILED_PRECONDITION while the job
        runs or when it failed, NOT_FOUND for an unknown id)."""
        info, result_json, result_dir = _robodiff.job_result(self._native, job_id)
        return JobResult(info, json.loads(result_json) if result_json else {}, result_dir)

    def wait_job(self, job_id: str, timeout: Optional[float] = None, poll: float = 0.1) -> JobInfo:
        """Polls job_status every ``poll`` seconds until the job is final; returns its last
        status. Raises TimeoutError naming the job and its state after ``timeout`` seconds."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            info = self.job_status(job_id)
            if info.done:
                return info
            if deadline is not None and time.monotonic() >= deadline:
                raise TimeoutError(f"job {job_id} still {info.state} ({info.progress:.0%}) after {timeout} s")
            time.sleep(poll)


__all__ = ["JobInfo", "JobResult", "JobsMixin"]
