"""Where the pmg repository is, for the training tools.

The environment reads the robot (config/robots/g1/), the PMG clips (config/clips/g1/) and the GCO
leg model (training/pmg_train/gco_g1.json) by paths relative to the repository root, so the tools
run from a checkout: install the package editable (`pip install -e training[...]`) or run the
scripts from the checkout.
"""
from __future__ import annotations

import os

ENV_VAR = "PMG_REPO"
MARKER = os.path.join("config", "robots", "g1", "g1.yaml")


def _is_repo(path: str) -> bool:
    return os.path.isfile(os.path.join(path, MARKER))


def repo_root(explicit: str | None = None) -> str:
    """Absolute path of the pmg checkout.

    Looked up in this order: @p explicit (a --repo argument), $PMG_REPO, the checkout this package
    lives in (editable install or the scripts run in place), the current directory.
    Raises FileNotFoundError naming every place looked at when none holds config/robots/g1/g1.yaml.
    """
    candidates = []
    if explicit:
        candidates.append(("--repo", explicit))
    if os.environ.get(ENV_VAR):
        candidates.append((f"${ENV_VAR}", os.environ[ENV_VAR]))
    candidates.append(("package location", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")))
    candidates.append(("current directory", os.getcwd()))
    for origin, path in candidates:
        if _is_repo(path):
            return os.path.abspath(path)
        if origin in ("--repo", f"${ENV_VAR}"):  # an explicit choice that is wrong is an error, not a fallback
            raise FileNotFoundError(f"{origin} = {path!r} is not a pmg checkout (no {MARKER} there)")
    looked = ", ".join(f"{o} {os.path.abspath(p)!r}" for o, p in candidates)
    raise FileNotFoundError(f"pmg checkout not found (looked for {MARKER} in: {looked}); install pmg-train "
                            f"editable from the checkout (pip install -e training[cuda]), run from the checkout, "
                            f"or pass --repo / set ${ENV_VAR}")
