# Stage 2d: coexisting motions and their basins (bouncedisk.studies.basins; `bouncedisk basins`):
# the basin map in shard jobs joined with a check that every start appears once, and the
# start-up under load (fraction of starts from rest reaching the fast branch against the load).
# (only when the config has a `basins` section: a pipeline without it builds the rest)
BASINS = config.get("basins")

if BASINS:

    rule basins_shard:
        """One contiguous block of the basin map's starts: results/basins/map/shard-<i>.nc."""
        input:
            scene=scene_path(BASINS["scene"]),
            compiled=rules.compile_engine.output,
        output:
            f"{RES}/basins/map/shard-{{shard}}.nc",
        conda:
            "../envs/bouncedisk.yaml"
        log:
            f"{RES}/logs/basins/map-{{shard}}.log",
        benchmark:
            f"{RES}/benchmarks/basins/map-shard-{{shard}}.tsv"
        params:
            spec=BASINS["map"],
        wildcard_constraints:
            shard=r"\d+",
        script:
            "../scripts/basins_shard.py"


    rule basins_join:
        """The basin map's shards joined (every start once) and grouped: results/basins/map.nc."""
        input:
            compiled=rules.compile_engine.output,
            shards=expand(
                f"{RES}/basins/map/shard-{{i}}.nc", i=range(BASINS["map"]["shards"])
            ),
        output:
            f"{RES}/basins/map.nc",
        conda:
            "../envs/bouncedisk.yaml"
        log:
            f"{RES}/logs/basins/map-join.log",
        benchmark:
            f"{RES}/benchmarks/basins/map-join.tsv"
        script:
            "../scripts/basins_join.py"


    rule basins_startup:
        """Start-up under load: results/basins/startup.nc."""
        input:
            scene=scene_path(BASINS["scene"]),
            compiled=rules.compile_engine.output,
        output:
            f"{RES}/basins/startup.nc",
        conda:
            "../envs/bouncedisk.yaml"
        log:
            f"{RES}/logs/basins/startup.log",
        benchmark:
            f"{RES}/benchmarks/basins/startup.tsv"
        params:
            spec=BASINS["startup"],
        script:
            "../scripts/basins_startup.py"
