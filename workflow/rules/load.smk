# Stage 2c: the motor under load (docs/model.md "The motor under load"): torque-speed curves by
# continuation, both branches, with the energy audit (bouncedisk.studies.torque_speed).
import re


rule torque_speed:
    """Load characteristic of a scene (`bouncedisk torque-speed`): results/load/<curve>.nc."""
    input:
        scene=lambda wildcards: scene_path(config["load_curves"][wildcards.curve]["scene"]),
        compiled=rules.compile_engine.output,
    output:
        f"{RES}/load/{{curve}}.nc",
    wildcard_constraints:
        curve="|".join(re.escape(k) for k in config["load_curves"]) or "^$",
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/load/{{curve}}.log",
    benchmark:
        f"{RES}/benchmarks/load/{{curve}}.tsv"
    params:
        spec=lambda wildcards: config["load_curves"][wildcards.curve],
    priority: 3  # several seconds: before the 1-s jobs, which then fill the cores at the end
    threads: 1
    script:
        "../scripts/torque_speed.py"


rule torque_speed_prototype:
    """Load characteristic of the fitted prototype motor in SI units: results/load/prototype.nc.
    The motor's drive and Phi0 are the fit's (its run-ups'), its rotor and preload those of the
    prototype's load curve (prototype.load_curve: without one, the rotor is unknown)."""
    input:
        fit=f"{RES}/fit/prototype.nc",
        curve=LOAD_INPUTS,
        compiled=rules.compile_engine.output,
    output:
        f"{RES}/load/prototype.nc",
    priority: 90  # on the longest chain (after the fit, before its figure and the checks)
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/load/prototype.log",
    benchmark:
        f"{RES}/benchmarks/load/prototype.tsv"
    params:
        spec=config["prototype_load"],
    threads: 1
    script:
        "../scripts/torque_speed_prototype.py"


rule synthetic_load_curve:
    """Regenerate the shipped synthetic load curve (and log whether it is byte-identical)."""
    input:
        spec="workflow/config/synthetic_motor.yaml",
        compiled=rules.compile_engine.output,
    output:
        csv=f"{RES}/prototype/synthetic_motor_load.csv",
        yaml=f"{RES}/prototype/synthetic_motor_load.yaml",
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/synthetic_load_curve.log",
    benchmark:
        f"{RES}/benchmarks/synthetic_load_curve.tsv"
    params:
        shipped="data/prototype/synthetic_motor_load.csv",
    script:
        "../scripts/make_synthetic_load_curve.py"
