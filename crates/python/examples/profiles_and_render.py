# %% [markdown]
# # Subsurface scattering from Python
#
# Radial profiles of three diffusion models against the Monte Carlo random walk, then a
# built-in scene rendered into a numpy array. Run it as a script (`python
# profiles_and_render.py [OUT_DIR]`) or cell by cell in an editor that understands `# %%`.
# matplotlib is optional: without it the figures are skipped and the numbers still printed.

# %%
import pathlib
import sys

import numpy as np

import sss

out_dir = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
out_dir.mkdir(parents=True, exist_ok=True)
try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    plt = None
    print("matplotlib is not installed: figures are skipped")

# %% [markdown]
# ## Profiles: three models against Monte Carlo (skin1, Jensen et al. 2001)

# %%
preset = "skin1"
r_mc, rd_mc, se_mc = sss.monte_carlo(
    preset=preset,
    r_max=6.0,
    bins=60,
    photons=200_000,
    progress=lambda done, total: print(f"\rMonte Carlo {done}/{total} photons", end=""),
)
print()
models = {kind: sss.Model(kind, preset=preset) for kind in ["standard-dipole", "better-dipole", "pbd"]}
for kind, m in models.items():
    rd = m.rd(r_mc)
    # Where Monte Carlo is well resolved, how far is each model from it?
    ok = rd_mc[:, 0] > 10 * se_mc[:, 0]
    err = np.abs(rd[ok] / rd_mc[ok] - 1).mean(axis=0)
    print(f"{kind:>16}: R = {np.round(m.total_diffuse_reflectance, 4)}, "
          f"mean |model/MC - 1| per channel {np.round(err, 3)}")

if plt is not None:
    fig, axes = plt.subplots(1, 3, figsize=(13, 4), sharey=True)
    for ch, (ax, name) in enumerate(zip(axes, ["red", "green", "blue"])):
        ax.errorbar(r_mc, rd_mc[:, ch], yerr=se_mc[:, ch], fmt=".k", ms=3, label="Monte Carlo")
        r = np.linspace(0.01, 6.0, 400)
        for kind, m in models.items():
            ax.plot(r, m.rd(r)[:, ch], label=kind)
        ax.set_yscale("log")
        ax.set_xlabel("r (mm)")
        ax.set_title(f"{preset}, {name}")
    axes[0].set_ylabel("R_d (1/mm²)")
    axes[0].legend()
    fig.tight_layout()
    fig.savefig(out_dir / "profiles.png", dpi=100)
    print("wrote", out_dir / "profiles.png")

# %% [markdown]
# ## A built-in scene into an array

# %%
out = sss.render("sphere", method="separable", kernel="preintegrated",
                 progress=lambda done, total: None)
img = out["total"]  # float32 (H, W, 3), linear RGB
print("image", img.shape, img.dtype, "mean", img.mean(axis=(0, 1)))
print("stages (s):", {k: round(v, 4) for k, v in out["stages"].items()})
reference = sss.render("sphere", method="exact")
print("separable vs exact:", {k: v for k, v in sss.diff(out["subsurface"], reference["subsurface"]).items()})

if plt is not None:
    tone = np.clip(img / np.percentile(img, 99.5), 0, 1) ** (1 / 2.2)
    plt.figure(figsize=(5, 4))
    plt.imshow(tone)
    plt.axis("off")
    plt.savefig(out_dir / "sphere.png", dpi=100, bbox_inches="tight")
    print("wrote", out_dir / "sphere.png")
