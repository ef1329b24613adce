"""Fine-tuning a trained actor whose full Brax state was not kept.

A run keeps `actor.npz` (the actor's layers and its observation normaliser: what the ONNX export and the
controller need) beside `params.pkl` (normaliser, policy and value network: what `--restore` needs). Many
results in `training/results/` keep only the actor. `graft_actor` builds a Brax restore tuple from such an
actor and another run's `params.pkl`, which lends the critic (the value network) and the normaliser of the
critic's privileged observations. The lent critic was fitted to another actor's returns, so
`with_frozen_policy` lets a first stage fit the critic alone (`train_pmg.py --critic-warmup-steps`).

Shapes: the actor's observation `state` has n_obs entries (62 for the G1 legs), its last layer 2 n_act
outputs (mean and scale of n_act = 12 leg actions); the critic reads `privileged_state` (90 entries).
"""
import numpy as np


def _fail(path, field, expected, got):
    raise ValueError(f"{path}: {field} is {got}; expected {expected}")


def graft_actor(actor_npz, critic_pkl, hidden, n_obs, n_act, n_priv, action_scale=None, mode=None):
    """(normaliser, policy, value) for Brax's ppo.train(restore_params=...).

    actor_npz: an actor.npz written by train_pmg.save_params (obs_mean, obs_std [n_obs], w0..wL, b0..bL).
    critic_pkl: a params.pkl (Brax's tuple, numpy leaves) of a run with the same observation layout.
    hidden: the run's hidden layer sizes (--hidden), which the actor's layers must have.
    n_obs, n_act: the run's actor observation size and leg action count.
    n_priv: the run's critic observation size (privileged_state), which the critic's must equal.
    action_scale: the run's leg action scale [rad], or None to skip; the actor's must equal it (within 1e-6),
        since the actor's outputs are in units of it (train_pmg.py --action-scale-from keeps an earlier scale).
    mode: the run's reference mode (e.g. "pmg_gco"), or None to skip; the actor's must equal it.

    The normaliser is the critic run's (its count, the privileged statistics) with the actor's own `state`
    mean and standard deviation, its summed variance set to match (std^2 - std_eps) x count, so that Brax's
    running update carries the actor's statistics on. Raises ValueError naming the file and the field."""
    import pickle
    with np.load(actor_npz) as z:
        actor = {k: z[k] for k in z.files}
    for field in ("obs_mean", "obs_std", "w0", "b0"):
        if field not in actor:
            _fail(actor_npz, field, "present (an actor.npz of train_pmg.py)", "missing")
    if mode is not None and "mode" in actor and str(actor["mode"]) != mode:
        _fail(actor_npz, "mode", f"{mode!r} (this run's --mode)", repr(str(actor["mode"])))
    n_layers = sum(1 for k in actor if k.startswith("w") and k[1:].isdigit())
    sizes = [n_obs, *hidden, 2 * n_act]
    if n_layers != len(sizes) - 1:
        _fail(actor_npz, "layer count", f"{len(sizes) - 1} (--hidden {','.join(map(str, hidden))} and an output)",
              n_layers)
    for i in range(n_layers):
        w, b = actor[f"w{i}"], actor[f"b{i}"]
        if w.shape != (sizes[i], sizes[i + 1]) or b.shape != (sizes[i + 1],):
            _fail(actor_npz, f"w{i}/b{i}", f"shapes {(sizes[i], sizes[i + 1])}/{(sizes[i + 1],)}",
                  f"{w.shape}/{b.shape}")
        if not (np.all(np.isfinite(w)) and np.all(np.isfinite(b))):
            _fail(actor_npz, f"w{i}/b{i}", "finite", "not finite")
    mean, std = actor["obs_mean"], actor["obs_std"]
    if mean.shape != (n_obs,) or std.shape != (n_obs,):
        _fail(actor_npz, "obs_mean/obs_std", f"shape ({n_obs},)", f"{mean.shape}/{std.shape}")
    if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(std)) and np.all(std > 0)):
        _fail(actor_npz, "obs_std", "finite and > 0", "not")
    if action_scale is not None:
        if "action_scale" not in actor:
            _fail(actor_npz, "action_scale", "present", "missing")
        got = np.asarray(actor["action_scale"], float)
        want = np.asarray(action_scale, float)
        if got.shape != want.shape or np.max(np.abs(got - want)) > 1e-6:
            _fail(actor_npz, "action_scale", f"this run's {np.round(want, 4).tolist()} (pass --action-scale-from "
                  "the actor's train_config.json)", np.round(got, 4).tolist())

    with open(critic_pkl, "rb") as f:
        try:
            norm, _, value = pickle.load(f)
        except (ValueError, TypeError) as e:
            raise ValueError(f"{critic_pkl}: expected a params.pkl of train_pmg.py (normaliser, policy, value): {e}")
    key = "privileged_state"  # the state entry is replaced by the actor's own below
    if key not in norm.mean or np.shape(norm.mean[key]) != (n_priv,):
        _fail(critic_pkl, f"normaliser mean[{key!r}]", f"shape ({n_priv},)",
              np.shape(norm.mean[key]) if key in norm.mean else "missing")
    vh = [np.shape(value["params"][f"hidden_{i}"]["kernel"]) for i in range(len(value["params"]))]
    if vh[0][0] != n_priv or [s[1] for s in vh[:-1]] != list(hidden) or vh[-1][1] != 1:
        _fail(critic_pkl, "value network layers", f"{n_priv} inputs, hidden {list(hidden)} and one output", vh)
    count = float(np.asarray(norm.count.hi, np.float64)) * 2.0 ** 32 + float(np.asarray(norm.count.lo, np.float64)) \
        if hasattr(norm.count, "hi") else float(np.asarray(norm.count))
    if count < 1.0:
        _fail(critic_pkl, "normaliser count", ">= 1", count)
    dtype = np.asarray(norm.mean["state"]).dtype
    mean_d = dict(norm.mean, state=mean.astype(dtype))
    std_d = dict(norm.std, state=std.astype(dtype))
    sv_d = dict(norm.summed_variance,
                state=(np.maximum(std.astype(np.float64) ** 2 - float(norm.std_eps), 0.0) * count).astype(dtype))
    norm = norm.replace(mean=mean_d, std=std_d, summed_variance=sv_d)
    policy = {"params": {f"hidden_{i}": {"kernel": actor[f"w{i}"], "bias": actor[f"b{i}"]} for i in range(n_layers)}}
    return norm, policy, value


def with_frozen_policy(compute_ppo_loss):
    """Brax's compute_ppo_loss (or a wrapper of it, e.g. symmetry.with_mirror_loss) with the policy's
    parameters behind a stop-gradient: the loss and its metrics are unchanged, its gradient with respect to
    the policy is exactly zero, so Adam leaves the actor as it is while the critic (value loss) learns."""
    import jax

    def loss(params, normalizer_params, data, rng, ppo_network, **kwargs):
        params = params.replace(policy=jax.lax.stop_gradient(params.policy))
        return compute_ppo_loss(params, normalizer_params, data, rng, ppo_network, **kwargs)

    return loss

