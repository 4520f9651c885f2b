"""The first place where a mapping breaks a JSON schema, as one line (the pipeline's config).

Snakemake's own report of an invalid config prints the whole schema after the error; the
pipeline prints this line instead, naming the key (``bouncedisk: error: pipeline config:
tracking: ...``), and exits with status 2 like the package's commands.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from pathlib import Path

import yaml


def schema_error(data: Mapping, schema_path: str | Path) -> str | None:
    """The most relevant violation of a JSON schema by ``data``, as one line.

    ``jsonschema`` comes with Snakemake, the only caller's; it is imported here, not by the
    package.

    Parameters
    ----------
    data : Mapping
        The mapping checked (the pipeline's config).
    schema_path : str or Path
        The schema, a YAML file (``workflow/schemas/config.schema.yaml``).

    Returns
    -------
    str or None
        ``"key.sub: what is wrong"`` (``(top level)`` for the mapping itself), or ``None`` when
        ``data`` is valid.
    """
    import jsonschema

    err = jsonschema.exceptions.best_match(_validator(str(schema_path)).iter_errors(dict(data)))
    if err is None:
        return None
    where = ".".join(str(k) for k in err.absolute_path) or "(top level)"
    return f"{where}: {err.message}"


@functools.cache
def _validator(schema_path: str):
    """The JSON-schema validator of a YAML schema file, read once per process (the Snakefile
    converts the config's numbers, then checks it)."""
    import jsonschema

    schema = yaml.safe_load(Path(schema_path).read_text(encoding="utf-8"))
    return jsonschema.validators.validator_for(schema)(schema)


def numbers_from_text(data: dict, schema_path: str | Path) -> None:
    """In place: every text value where the schema asks for a number (or an integer, and the
    text is a whole number) and ``float()`` reads it becomes that number.

    YAML 1.1, which PyYAML and so Snakemake read, takes ``1e-9`` (no dot) for text, and
    Snakemake's ``--config KEY='{members: 8}'`` gives nested values as text; a scene file takes
    any number ``float()`` reads, and so does the pipeline's config. A value the schema also
    allows as text is left alone.
    """
    validator = _validator(str(schema_path))
    for _ in range(10_000):  # one value per pass at least; a config has far fewer
        fixes = [fix for err in validator.iter_errors(data) for fix in _number_fixes(err)]
        if not fixes:
            return
        for path, value in fixes:
            target = data
            for key in path[:-1]:
                target = target[key]
            target[path[-1]] = value


def _number_fixes(err) -> list[tuple[list, float | int]]:
    """``(path, number)`` for a type error on text that is the number the schema wants (and for
    each error inside an ``anyOf``/``oneOf``)."""
    out = [fix for sub in err.context or () for fix in _number_fixes(sub)]
    wanted = err.validator_value if err.validator == "type" else ()
    wanted = {wanted} if isinstance(wanted, str) else set(wanted)
    if not isinstance(err.instance, str) or not wanted & {"number", "integer"}:
        return out
    if "string" in wanted or not err.absolute_path:
        return out
    try:
        x = float(err.instance.strip())
    except ValueError:
        return out
    if not math.isfinite(x):  # "nan" or "inf": a mistake the schema's bounds would not see
        return out
    if "number" not in wanted:  # an integer: a whole number only
        if not (x.is_integer() and abs(x) < 2**63):
            return out
        x = int(x)
    return [*out, (list(err.absolute_path), x)]
