"""The tracked runs, read back from the MLflow store (``bouncedisk runs``).

Reading side of :mod:`bouncedisk.tracking`: list the top-level runs (pipeline invocations and
tracked commands) with what changed since the previous one, show one run, and diff two runs'
params, metrics and output hashes; the store keeps them after the files are gone.
"""

from __future__ import annotations

import datetime as _dt
import json
import socket
import tempfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from ..io.provenance import TAG_GIT_COMMIT, TAG_GIT_DIRTY, TAG_VERSION
from ..model.errors import InputError
from . import store, writing

# tags worth comparing between runs (not pid, host, process start)
COMPARED_TAGS = (
    TAG_GIT_COMMIT,
    TAG_GIT_DIRTY,
    TAG_VERSION,
    "snakemake_version",
    "python_version",
    "cores",
)

# metrics of the invocation itself (wall time, jobs run, tracking cost), not of its outputs
INVOCATION_METRICS = ("pipeline.", "tracking.")


class Runs:
    """The top-level runs of one store's experiment, oldest first."""

    def __init__(
        self, uri: str | None = None, results: str | Path = "results", experiment: str | None = None
    ):
        self.store = store.resolve_store(uri, results, experiment)
        store.preflight(self.store, create=False)
        try:
            self.client = store._client(self.store)
            exp = store.experiment_id(self.client, self.store, create=False)
            self.runs = [] if exp is None else self._search(exp)
            #: The store's other experiments (a listing that finds none names them).
            self.others = sorted(
                e.name
                for e in self.client.search_experiments()
                if e.name not in (self.store.experiment, "Default")
            )
        except store.TrackingError:
            raise
        except Exception as ex:  # noqa: BLE001 - drivers and REST raise their own types
            raise store.TrackingError(
                self.store.uri, f"cannot be read: {store.one_line(ex)}"
            ) from None
        self.runs.sort(key=lambda r: r.info.start_time or 0)

    def _search(self, exp: str) -> list:
        out, token = [], None
        while True:
            page = self.client.search_runs([exp], max_results=1000, page_token=token)
            out.extend(r for r in page if "mlflow.parentRunId" not in r.data.tags)
            token = page.token
            if not token:
                return out

    def find(self, key: str):
        """A run by MLflow id (or unique prefix), run name, or the bouncedisk ``run_id`` of its
        output (as ``bouncedisk simulate`` prints it). Raises InputError (exit 2)."""
        key = key.strip()
        exact = [
            r
            for r in self.runs
            if key in (r.info.run_id, r.info.run_name, r.data.tags.get(writing.TAG_RUN_ID))
        ]
        hits = exact or [
            r
            for r in self.runs
            if len(key) >= 4
            and (
                r.info.run_id.startswith(key)
                or r.data.tags.get(writing.TAG_RUN_ID, "").startswith(key)
            )
        ]
        if not hits:
            short = " (a prefix needs at least 4 characters)" if len(key) < 4 else ""
            raise InputError(f"tracking store {self.store.uri}", key, f"no run with this id{short}")
        if len(hits) > 1:
            raise InputError(
                f"tracking store {self.store.uri}",
                key,
                f"matches {len(hits)} runs; give more of the run id",
            )
        return hits[0]

    def previous(self, run):
        """The run of the same kind before ``run`` (None for the first)."""
        kind = run.data.tags.get(writing.TAG_KIND)
        before = [
            r
            for r in self.runs
            if r.data.tags.get(writing.TAG_KIND) == kind
            and (r.info.start_time or 0) < (run.info.start_time or 0)
        ]
        return before[-1] if before else None

    def children(self, run) -> list:
        """The nested (per-job) runs of a pipeline run."""
        rid = run.info.run_id
        return list(
            self.client.search_runs(
                [run.info.experiment_id],
                filter_string=f"tags.mlflow.parentRunId = '{rid}'",
                max_results=5000,
            )
        )

    def manifest(self, run) -> dict[str, dict]:
        """The run's ``outputs.json``: output path -> sha256, bytes (empty if missing)."""
        try:
            with tempfile.TemporaryDirectory() as tmp:
                p = self.client.download_artifacts(run.info.run_id, "outputs.json", tmp)
                return json.loads(Path(p).read_text())
        except Exception:  # noqa: BLE001 - an artifact store that lost it: no hashes
            return {}


def status(run) -> str:
    """The run's status; a RUNNING run whose process on this host is gone reads KILLED."""
    st = run.info.status
    if st == "RUNNING":
        t = run.data.tags
        pid = t.get(writing.TAG_PID, "")
        if t.get(writing.TAG_HOST) == socket.gethostname() and pid.isdigit():
            if not writing.process_alive(int(pid), t.get(writing.TAG_PSTART, "")):
                return "KILLED"
    return st


def _when(ms: int | None) -> str:
    if not ms:
        return ""
    return _dt.datetime.fromtimestamp(ms / 1000, _dt.UTC).strftime("%Y-%m-%d %H:%M:%SZ")


def job_of(key: str) -> str:
    """The pipeline job a snapshot key belongs to: ``simulations/fig4/r_phi`` ->
    ``simulations/fig4``; ``""`` for a key of the run itself (a tracked command's ``e``)."""
    return key.rpartition("/")[0]


def jobs_of(d: dict) -> set[str]:
    """The jobs a run's params (or metrics) snapshot holds."""
    return {job_of(k) for k in d} - {""}


def comparable(a: dict, b: dict) -> tuple[dict, dict]:
    """``a`` and ``b`` cut to the keys of the jobs both runs hold (and the runs' own keys).

    A pipeline run's snapshot holds the jobs of its DAG only: after an invocation that redrew
    one figure, the other jobs are absent from it, not changed.
    """
    common = jobs_of(a) & jobs_of(b) | {""}
    return (
        {k: v for k, v in a.items() if job_of(k) in common},
        {k: v for k, v in b.items() if job_of(k) in common},
    )


def changed_keys(a: dict[str, str] | None, b: dict[str, str]) -> list[str]:
    """Keys whose values differ between two param dicts, over the jobs both hold (None:
    everything is new)."""
    if a is None:
        return []
    a, b = comparable(a, b)
    return sorted(k for k in set(a) | set(b) if a.get(k) != b.get(k))


def summarize_changes(keys: Iterable[str], width: int = 60) -> str:
    """``simulations/fig4: r_phi, scene_sha256; …`` grouped by output."""
    groups: dict[str, list[str]] = {}
    for k in keys:
        head, _, tail = k.rpartition("/")
        groups.setdefault(head or "run", []).append(tail)
    text = "; ".join(f"{g}: {', '.join(v)}" for g, v in groups.items())
    return text if len(text) <= width else text[: width - 1] + "…"


def row(runs: Runs, run) -> dict[str, Any]:
    """One run as a plain record (for the listing and ``--json``)."""
    t, m = run.data.tags, run.data.metrics
    prev = runs.previous(run)
    changed = changed_keys(prev.data.params if prev else None, run.data.params)
    passed, total = m.get("checks.passed"), m.get("checks.total")
    return {
        "run_id": run.info.run_id,
        "name": run.info.run_name,
        "kind": t.get(writing.TAG_KIND, ""),
        "status": status(run),
        "start": _when(run.info.start_time),
        "end": _when(run.info.end_time),
        "git_commit": t.get(TAG_GIT_COMMIT, ""),
        "git_dirty": t.get(TAG_GIT_DIRTY, ""),
        "jobs_run": int(m["pipeline.jobs_run"]) if "pipeline.jobs_run" in m else None,
        "checks_passed": int(passed) if passed is not None else None,
        "checks_total": int(total) if total is not None else None,
        "previous": prev.info.run_id if prev else None,
        "changed": changed,
        "output_run_id": t.get(writing.TAG_RUN_ID),
    }


def format_list(rows: list[dict]) -> str:
    """The listing for a terminal, newest first."""
    if not rows:
        return "(no runs recorded yet)"
    head = (
        f"{'run':<12}  {'started (UTC)':<20}  {'kind':<8}  {'status':<8}  {'commit':<13}  "
        f"{'checks':<6}  changed since previous"
    )
    lines = [head]
    for r in reversed(rows):
        commit = (r["git_commit"] or "")[:12] + ("*" if r["git_dirty"] == "true" else "")
        checks = f"{r['checks_passed']}/{r['checks_total']}" if r["checks_total"] else ""
        if r["previous"] is None:
            what = "(first)"
        else:
            what = summarize_changes(r["changed"]) or "(no parameter changed)"
        lines.append(
            f"{r['run_id'][:12]:<12}  {r['start']:<20}  {r['kind']:<8}  {r['status']:<8}  "
            f"{commit:<13}  {checks:<6}  {what}"
        )
    lines.append("(* uncommitted changes; `bouncedisk runs show RUN`, `bouncedisk runs diff A B`)")
    return "\n".join(lines)


def show(runs: Runs, run) -> dict[str, Any]:
    """Everything recorded of one run."""
    rec = row(runs, run)
    rec["tags"] = {k: v for k, v in sorted(run.data.tags.items()) if not k.startswith("mlflow.")}
    rec["params"] = dict(sorted(run.data.params.items()))
    rec["metrics"] = dict(sorted(run.data.metrics.items()))
    rec["outputs"] = runs.manifest(run)
    rec["jobs"] = [
        {
            "run_id": c.info.run_id,
            "name": c.info.run_name,
            "kind": c.data.tags.get(writing.TAG_KIND, ""),
            "status": c.info.status,
            "wall_s": c.data.metrics.get("benchmark.s"),
            "max_rss_mb": c.data.metrics.get("benchmark.max_rss"),
        }
        for c in sorted(runs.children(run), key=lambda c: c.info.run_name or "")
    ]
    return rec


def format_show(rec: dict[str, Any]) -> str:
    """One run for a terminal."""
    dirty = " (uncommitted changes)" if rec["git_dirty"] == "true" else ""
    lines = [
        f"run {rec['run_id']} ({rec['name']})",
        f"  kind {rec['kind']}, status {rec['status']}, {rec['start']} -> {rec['end'] or '…'}",
        f"  commit {rec['git_commit']}{dirty}",
    ]
    if rec["checks_total"]:
        lines.append(f"  checks {rec['checks_passed']} of {rec['checks_total']} pass")
    for title, d in (("tags", rec["tags"]), ("params", rec["params"]), ("metrics", rec["metrics"])):
        lines.append(f"{title} ({len(d)}):")
        lines += [f"  {k} = {v}" for k, v in d.items()]
    lines.append(f"outputs ({len(rec['outputs'])}):")
    lines += [
        f"  {k}  sha256 {v.get('sha256', '')[:16]}" for k, v in sorted(rec["outputs"].items())
    ]
    if rec["jobs"]:
        lines.append(f"jobs ({len(rec['jobs'])}):")
        for j in rec["jobs"]:
            wall = f"{j['wall_s']:.2f} s" if j["wall_s"] is not None else ""
            rss = f"{j['max_rss_mb']:.0f} MB" if j["max_rss_mb"] is not None else ""
            lines.append(f"  {j['run_id'][:12]}  {j['name']}  {j['status']}  {wall}  {rss}")
    return "\n".join(lines)


def _pairs(a: dict, b: dict, same=lambda x, y: x == y) -> dict[str, list]:
    return {
        k: [a.get(k), b.get(k)] for k in sorted(set(a) | set(b)) if not same(a.get(k), b.get(k))
    }


def diff(runs: Runs, ra, rb) -> dict[str, Any]:
    """What differs between two runs: params, metrics (the invocation's own ``pipeline.*`` and
    ``tracking.*`` apart, under "pipeline"), output hashes, and code/tool tags."""
    own = INVOCATION_METRICS
    ma = {k: v for k, v in ra.data.metrics.items() if not k.startswith(own)}
    mb = {k: v for k, v in rb.data.metrics.items() if not k.startswith(own)}
    pa = {k: v for k, v in ra.data.metrics.items() if k.startswith(own)}
    pb = {k: v for k, v in rb.data.metrics.items() if k.startswith(own)}
    fa = {k: v.get("sha256") for k, v in runs.manifest(ra).items()}
    fb = {k: v.get("sha256") for k, v in runs.manifest(rb).items()}
    ta = {k: ra.data.tags.get(k) for k in COMPARED_TAGS if k in ra.data.tags}
    tb = {k: rb.data.tags.get(k) for k in COMPARED_TAGS if k in rb.data.tags}
    # only the jobs both runs hold are compared; the others are named, not called changed
    jobs_a = jobs_of(ra.data.params) | jobs_of(ma)
    jobs_b = jobs_of(rb.data.params) | jobs_of(mb)
    common = jobs_a & jobs_b
    fa = {k: v for k, v in fa.items() if k in fb or _file_job(k) in common}
    fb = {k: v for k, v in fb.items() if k in fa or _file_job(k) in common}
    return {
        "a": ra.info.run_id,
        "b": rb.info.run_id,
        "params": _pairs(*comparable(ra.data.params, rb.data.params)),
        "metrics": _pairs(*comparable(ma, mb)),
        "outputs": _pairs(fa, fb),
        "tags": _pairs(ta, tb),
        "pipeline": _pairs(pa, pb),
        "jobs_only_in_a": sorted(jobs_a - jobs_b),
        "jobs_only_in_b": sorted(jobs_b - jobs_a),
    }


def _file_job(path: str) -> str:
    """The job key of an output file (``simulations/fig4.nc`` -> ``simulations/fig4``)."""
    p = Path(path)
    return str(p.with_suffix("")) if p.suffix else str(p)


def format_diff(d: dict[str, Any]) -> str:
    """A diff for a terminal: one line per differing key, ``A | B``."""

    def fmt(v: Any) -> str:
        if v is None:
            return "—"
        if isinstance(v, float):
            return f"{v:.10g}"
        return str(v)[:70]

    lines = [f"A = {d['a']}", f"B = {d['b']}"]
    n = 0
    for section in ("params", "metrics", "outputs", "tags", "pipeline"):
        items = d[section]
        if not items:
            continue
        lines.append(f"{section} that differ ({len(items)}):")
        for k, (va, vb) in items.items():
            if section == "outputs":
                va, vb = (va or "")[:12] or None, (vb or "")[:12] or None
            lines.append(f"  {k}: {fmt(va)} | {fmt(vb)}")
        if section != "pipeline":
            n += len(items)
    for key, who, other in (("jobs_only_in_a", "A", "B"), ("jobs_only_in_b", "B", "A")):
        jobs = d.get(key) or []
        if jobs:
            shown = ", ".join(jobs[:8]) + (f", … ({len(jobs) - 8} more)" if len(jobs) > 8 else "")
            lines.append(
                f"jobs of {who} that {other} did not run ({len(jobs)}; not compared): {shown}"
            )
    if n == 0:
        lines.append("(no params, metrics or outputs differ in the jobs both ran)")
    return "\n".join(lines)
