"""Tutorial: your own pantograph, lumped and rigid, from a data sheet to its modes.

    python docs/tutorials/own_pantograph.py [--out DIR] [--figures DIR]

Writes a three-mass parameter file from a data sheet and a rigid DSA-380 file with other
collector springs and damper into DIR (default ``tutorial-pantograph``), runs ``pantocosim
modal`` and ``pantocosim pantograph`` on them, checks the lumped model's frequencies against
the eigenvalues of its mass and stiffness matrices, and writes ``summary.json`` and the figure
``my-3mass-response.png`` (also into --figures when given).
"""

from __future__ import annotations

import argparse
import json
import shutil
import tomllib
from pathlib import Path

import numpy as np

from tutorial_cli import FILES, pantocosim  # (beside this script)

LUMPED = (FILES / "my-3mass.toml").read_text()


def chain_frequencies(path: Path) -> list[float]:
    """Undamped natural frequencies [Hz] of a chain file, from its M and K by hand."""
    chain = tomllib.loads(path.read_text())["chain"]
    m, k = np.array(chain["masses"]), np.array(chain["stiffness"])
    n = len(m)
    K = np.zeros((n, n))
    for i in range(n):          # spring i joins mass i to mass i+1 (the last to the roof)
        K[i, i] += k[i]
        if i + 1 < n:
            K[i + 1, i + 1] += k[i]
            K[i, i + 1] -= k[i]
            K[i + 1, i] -= k[i]
    w2 = np.linalg.eigvals(np.diag(1 / m) @ K)
    return sorted(float(np.sqrt(x.real) / (2 * np.pi)) for x in w2)


def rigid_variant(out: Path) -> Path:
    """The rigid DSA-380 preset with the collector springs and damper of another data sheet."""
    from pantocosim.pantograph.presets import preset_path

    # --8<-- [start:rigid]
    text = preset_path("dsa380-rigid").read_text()
    text = text.replace('name = "dsa380-rigid"', 'name = "my-dsa380"')
    text = text.replace("k_l = 8658.513709", "k_l = 12000.0")    # collector springs [N/m]
    text = text.replace("c = 42000.0", "c = 30000.0")            # damper [N s/m]
    (out / "my-dsa380.toml").write_text(text)
    # --8<-- [end:rigid]
    return out / "my-dsa380.toml"


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("tutorial-pantograph"))
    ap.add_argument("--figures", type=Path, default=None, help="also copy the figures here")
    args = ap.parse_args(argv)
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    (out / "my-3mass.toml").write_text(LUMPED)
    rigid_variant(out)

    # --8<-- [start:run]
    lumped = json.loads(pantocosim("modal", "my-3mass.toml", "--json", cwd=out))
    pantocosim("pantograph", "my-3mass.toml", "--force", "120 + 20*sin(2*pi*6*t)",
               "--duration", "3", "--out", "my-3mass-response", cwd=out)
    preset = json.loads(pantocosim("modal", "dsa380-rigid", "--json", cwd=out))
    mine = json.loads(pantocosim("modal", "my-dsa380.toml", "--json", cwd=out))
    # --8<-- [end:run]

    summary = {
        "lumped": {k: lumped[k] for k in ("frequencies_hz", "damping_ratios", "mode_labels")},
        "lumped_undamped_by_hand_hz": chain_frequencies(out / "my-3mass.toml"),
        "dsa380_rigid": {k: preset[k] for k in ("frequencies_hz", "damping_ratios",
                                                "mode_labels")},
        "my_dsa380": {k: mine[k] for k in ("frequencies_hz", "damping_ratios",
                                           "mode_labels")},
    }
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    print("my-3mass          f [Hz]   zeta   label      undamped, by hand [Hz]")
    for f, z, lab, f0 in zip(lumped["frequencies_hz"], lumped["damping_ratios"],
                             lumped["mode_labels"], summary["lumped_undamped_by_hand_hz"]):
        print(f"               {f:8.4f} {z:7.4f}   {lab:<12} {f0:8.4f}")
    print("rigid DSA-380     preset f [Hz] (zeta)    my-dsa380 f [Hz] (zeta)    label")
    for f, z, g, y, lab in zip(preset["frequencies_hz"], preset["damping_ratios"],
                               mine["frequencies_hz"], mine["damping_ratios"],
                               preset["mode_labels"]):
        print(f"               {f:8.4f} ({z:.4f})       {g:8.4f} ({y:.4f})        {lab}")
    pngs = sorted((out / "my-3mass-response").glob("*.png"))
    if args.figures and pngs:
        args.figures.mkdir(parents=True, exist_ok=True)
        shutil.copy(pngs[0], args.figures / "my-3mass-response.png")
    return summary


if __name__ == "__main__":
    main()
