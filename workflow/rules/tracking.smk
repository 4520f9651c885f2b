# Experiment tracking (MLflow, docs/formats.md "Experiment tracking"): one parent run per invocation
# that does work, a nested run per job that ran, all logged from the main Snakemake process by the
# Snakefile's onstart/onsuccess/onerror handlers (the jobs never import mlflow). A no-op run
# reaches no handler and logs nothing. `--config tracking='{enabled: false}'` runs untracked.
import signal
import sys

import snakemake as _snakemake

from bouncedisk.tracking import pipeline as _pipeline
from bouncedisk.tracking import store as _store

TRACKING = _pipeline.PipelineSettings.from_config(config)
_TRACKER = []  # the invocation's PipelineTracker, once onstart made it


def _tracking_jobs():
    """The DAG's jobs as plain records (src/ never imports snakemake)."""
    records = []
    for job in workflow.dag.jobs:
        if not job.output:
            continue
        records.append(
            _pipeline.JobRecord(
                job.rule.name,
                [str(o) for o in job.output],
                wildcards={k: str(v) for k, v in job.wildcards.items()},
                params={k: v for k, v in job.params.items() if not callable(v)},
                benchmark=str(job.benchmark) if job.benchmark else None,
                logs=[str(x) for x in job.log],
                ran=workflow.dag.needrun(job),
                name=FIGURE_JOB_NAMES.get(job.rule.name),  # a batch of figures: figures/<batch>
            )
        )
    return records


def _note_interrupt(signum):
    """Chain a signal handler that remembers the interrupt (KILLED rather than FAILED)."""
    previous = signal.getsignal(signum)

    def handler(sig, frame):
        for t in _TRACKER:
            t.interrupted = True
        if callable(previous):
            return previous(sig, frame)
        if sig == signal.SIGINT:
            raise KeyboardInterrupt

    try:
        signal.signal(signum, handler)
    except ValueError:  # not the main thread
        pass


def tracking_start():
    if not TRACKING.enabled or workflow.touch:  # --touch computes nothing worth a record
        return
    try:
        cores = workflow.cores
    except Exception:
        cores = None
    try:  # the store named (an unknown scheme), then reached: one report, no traceback
        tracker = _pipeline.PipelineTracker(
            TRACKING,
            RES,
            config,
            cores=cores,
            snakemake_version=_snakemake.__version__,
            command=" ".join(sys.argv),
        )
        tracker.start(_tracking_jobs())
    except _store.TrackingError as ex:
        print(_store.error_report(ex), file=sys.stderr, flush=True)
        raise SystemExit(1)
    _TRACKER.append(tracker)
    _note_interrupt(signal.SIGINT)
    _note_interrupt(signal.SIGTERM)


def tracking_finish():
    for tracker in _TRACKER:
        try:
            run_id = tracker.finish()
        except _store.TrackingError as ex:
            print(_store.error_report(ex), file=sys.stderr, flush=True)
            raise SystemExit(1)
        t = tracker.timings
        spent = t.get("tracking.start_s", 0) + t.get("tracking.finish_s", 0)
        print(
            f"bouncedisk: recorded run {run_id} in {tracker.store.uri} "
            f"({spent:.1f} s, and {t.get('tracking.open_s', 0):.1f} s alongside the jobs)",
            file=sys.stderr,
        )


def tracking_fail():
    for tracker in _TRACKER:
        try:
            tracker.fail()
        except _store.TrackingError as ex:
            print(_store.error_report(ex), file=sys.stderr, flush=True)
