"""The first place where a mapping breaks a JSON schema, as one line (the pipeline's config).

Snakemake's own report of an invalid config prints the whole schema after the error; the
pipeline prints this line instead, naming the key (``bouncedisk: error: pipeline config:
tracking: ...``), and exits with status 2 like the package's commands.
"""

from __future__ import annotations

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

    schema = yaml.safe_load(Path(schema_path).read_text(encoding="utf-8"))
    validator = jsonschema.validators.validator_for(schema)(schema)
    err = jsonschema.exceptions.best_match(validator.iter_errors(dict(data)))
    if err is None:
        return None
    where = ".".join(str(k) for k in err.absolute_path) or "(top level)"
    return f"{where}: {err.message}"
