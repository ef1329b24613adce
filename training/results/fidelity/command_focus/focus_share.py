import dataclasses, sys
sys.path.insert(0, "training")
import numpy as np, jax
from command_gap import roll
from pmg_train.g1_env import EnvConfig, G1PmgEnv
from train_pmg import command_envelopes_from
base = dataclasses.replace(EnvConfig(), vx=(-0.85, 1.25), vy=(-0.6, 0.6), wz=(-1.0, 1.0), height=(0.59, 0.78),
                           command_slew=True, p_stop=0.25, p_posture_walk=0.6, clips="config/clips/g1_walking_height",
                           **command_envelopes_from("config/controller/g1_sil_policy.yaml"))
for name, f in (("plain", {}), ("focus 0.1", dict(command_focus={"vx": (-0.6, -0.2), "height": (0.66, 0.76)}, p_focus=0.1))):
    u = np.asarray(roll(G1PmgEnv(dataclasses.replace(base, **f)), jax.random.PRNGKey(0), 1024, 1000))
    w = np.any(np.abs(u[..., :3]) > 0.01, -1)
    cb = w & (u[..., 0] < -0.25) & (u[..., 5] < 0.77)
    cb5 = w & (u[..., 0] < -0.4) & (u[..., 5] < 0.73)
    print(f"{name}: walking {w.mean():.3f} of steps; backward < -0.25 m/s below 0.77 m: {cb.sum()/w.sum():.3f}; "
          f"backward < -0.4 below 0.73 m: {cb5.sum()/w.sum():.3f} of the walking steps")
