"""Study (a) of issue 14 on the chapter-6 car: how stiff is stiff enough? Per chassis mode
(the others rigid) the smallest stiffness multiplier that keeps χ and the understeer
gradient within 2 % of the rigid car's over λ = 0.3-0.7, then all modes together
(experiments/studies/stiff_enough.toml; optimise.stiffness_requirement). Writes
``OUT/stiff_enough.json`` and ``OUT/stiff_enough.png``.

    python experiments/stiff_enough.py                    # results/stiff_enough/
    python experiments/stiff_enough.py --study my.toml --out DIR

The first run compiles the car's steady-state program (minutes on two cores); JAX's disk
cache keeps it.
"""

import argparse
import json
import os
from pathlib import Path

import jax

import optimise

STUDY = Path(__file__).with_name("studies") / "stiff_enough.toml"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--study", type=Path, default=STUDY, help="study file (TOML)")
    ap.add_argument("--out", type=Path, default=None, help="output folder (default: the file's [run] out)")
    args = ap.parse_args()
    folder = Path(os.environ.get("JAXVEH_CACHE", Path.home() / ".cache" / "jaxveh" / "jax"))
    jax.config.update("jax_compilation_cache_dir", str(folder))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 1.0)
    study = optimise.load_stiffness_study(args.study, out=args.out)
    result = optimise.stiffness_requirement(study, progress=lambda line: print(line, flush=True))
    files = optimise.write_stiffness_outputs(result)
    report = json.loads(Path(files["json"]).read_text())
    print(json.dumps({"per_mode": [{k: m[k] for k in ("mode", "mu_min", "status", "frequency_hz",
                                                      "nominal_frequency_hz", "binding_quantity", "binding_lambda")}
                                   for m in report["per_mode"]],
                      "nominal_worst_deviation": report["nominal_worst_deviation"], "joint": report["joint"],
                      "evaluations": report["evaluations"], "wall_s": report["wall_s"], "files": files}, indent=2))


if __name__ == "__main__":
    main()
