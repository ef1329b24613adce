#!/usr/bin/env python3
"""Fine-tuning an actor whose params.pkl was not kept (pmg_train/restore.py, train_pmg.py --restore-actor,
--restore-critic, --critic-warmup-steps), on small Brax PPO networks (62 -> 32-32 -> 2 x 12 actor, 90 -> 32-32 -> 1
critic, as the G1 env's observation layout):
1. graft_actor: the grafted actor's action distribution equals the original actor's on random observations (its
   layers and its `state` normaliser carried over), the critic and the privileged normaliser are the critic run's,
   and Brax's running update of the grafted normaliser keeps the actor's standard deviation (the summed variance
   matches the count) where a zero summed variance would collapse it.
2. Bad input is refused with the file and the field named: another --hidden, another action scale, another mode,
   a critic of another observation size, an actor.npz without its normaliser, a file that is no params.pkl.
3. with_frozen_policy around Brax's compute_ppo_loss on a synthetic batch: the same loss, a gradient of exactly
   zero for every policy parameter and a non-zero one for the critic, so Adam moves the critic alone.
4. train_pmg.main's staging with Brax's ppo.train recorded (nothing compiles): the critic stage from the graft with
   the frozen loss, then the rest from its parameters with the run's own loss; progress.jsonl and train_config.json.
5. train_pmg's command line: --restore-actor needs --restore-critic (and the reverse), excludes --restore;
   --critic-warmup-steps needs a restore, fewer steps than --timesteps, and no --warmup-steps.
Prints one line per check; exit 0 iff all pass."""
import contextlib
import io
import os
import pickle
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
from test_smoke_cpu import (CHILD, Checks, _MainStageReached, main_with_recorded_train, relaunch,  # noqa: E402
                            run_stages)
from test_symmetry import ppo_batch  # noqa: E402

N_OBS, N_ACT, N_PRIV, HIDDEN = 62, 12, 90, (32, 32)


def networks():
    from brax.training.acme import running_statistics
    from brax.training.agents.ppo import networks as ppo_networks
    return ppo_networks.make_ppo_networks({"state": (N_OBS,), "privileged_state": (N_PRIV,)}, N_ACT,
                                          preprocess_observations_fn=running_statistics.normalize,
                                          policy_hidden_layer_sizes=HIDDEN, value_hidden_layer_sizes=HIDDEN,
                                          policy_obs_key="state", value_obs_key="privileged_state")


def trained_run(net, rng, seed, obs_scale, obs_shift):
    """(normaliser, PPONetworkParams) as if a run had trained: random layers, statistics of 4096 observations."""
    import jax
    import jax.numpy as jnp
    from brax.training.acme import running_statistics, specs
    from brax.training.agents.ppo import losses as ppo_losses
    k1, k2 = jax.random.split(jax.random.PRNGKey(seed))
    params = ppo_losses.PPONetworkParams(policy=net.policy_network.init(k1), value=net.value_network.init(k2))
    spec = {"state": specs.Array((N_OBS,), jnp.float32), "privileged_state": specs.Array((N_PRIV,), jnp.float32)}
    norm = running_statistics.init_state(spec)
    for _ in range(4):
        norm = running_statistics.update(norm, {
            "state": jnp.asarray(rng.normal(size=(1024, N_OBS)) * obs_scale + obs_shift, jnp.float32),
            "privileged_state": jnp.asarray(rng.normal(size=(1024, N_PRIV)) * obs_scale - obs_shift, jnp.float32)})
    return norm, params


def write_actor(path, norm, params, action_scale, mode="pmg_gco", drop=()):
    """An actor.npz as train_pmg.save_params writes it (the fields restore.graft_actor reads)."""
    import numpy as np
    p = params.policy["params"]
    arrays = {"obs_mean": np.asarray(norm.mean["state"]), "obs_std": np.asarray(norm.std["state"]),
              "action_scale": np.asarray(action_scale, np.float32), "mode": np.array(mode)}
    for i in range(len(p)):
        arrays[f"w{i}"] = np.asarray(p[f"hidden_{i}"]["kernel"])
        arrays[f"b{i}"] = np.asarray(p[f"hidden_{i}"]["bias"])
    np.savez(path, **{k: v for k, v in arrays.items() if k not in drop})


def write_params(path, norm, params):
    import jax
    import numpy as np
    with open(path, "wb") as f:
        pickle.dump(jax.tree_util.tree_map(np.asarray, (norm, params.policy, params.value)), f)


def refused(check, what, fn, *needles):
    try:
        fn()
    except ValueError as e:
        msg = str(e)
        return check(all(n in msg for n in needles), f"{what} refused: {msg}")
    return check(False, f"{what} accepted")


def graft_checks(check, tmp, rng):
    import jax
    import jax.numpy as jnp
    import numpy as np
    from brax.training.acme import running_statistics
    from brax.training.agents.ppo import losses as ppo_losses
    from pmg_train.restore import graft_actor
    net = networks()
    a_norm, a_params = trained_run(net, rng, 1, 2.0, 0.5)      # the actor's run (its critic is lost)
    c_norm, c_params = trained_run(net, rng, 2, 0.7, -0.3)     # the run that lends its critic
    scale = rng.uniform(0.3, 1.0, N_ACT).astype(np.float32)
    actor, critic = os.path.join(tmp, "actor.npz"), os.path.join(tmp, "params.pkl")
    write_actor(actor, a_norm, a_params, scale)
    write_params(critic, c_norm, c_params)

    norm, policy, value = graft_actor(actor, critic, HIDDEN, N_OBS, N_ACT, N_PRIV, action_scale=scale,
                                      mode="pmg_gco")
    obs = {"state": jnp.asarray(rng.normal(size=(256, N_OBS)) * 2.0 + 0.5, jnp.float32),
           "privileged_state": jnp.asarray(rng.normal(size=(256, N_PRIV)), jnp.float32)}
    norm = jax.tree_util.tree_map(jnp.asarray, norm)
    want = np.asarray(net.policy_network.apply(a_norm, a_params.policy, obs))
    got = np.asarray(net.policy_network.apply(norm, policy, obs))
    err = float(np.max(np.abs(got - want)))
    check(err < 1e-5, f"the grafted actor's distribution equals the original's on 256 observations (max diff {err:.1e})")
    v_want = np.asarray(net.value_network.apply(c_norm, c_params.value, obs))
    v_got = np.asarray(net.value_network.apply(norm, value, obs))
    check(float(np.max(np.abs(v_got - v_want))) < 1e-5
          and np.array_equal(np.asarray(norm.mean["privileged_state"]), np.asarray(c_norm.mean["privileged_state"])),
          "the critic and the privileged normaliser are the critic run's")
    check(not np.allclose(np.asarray(c_norm.std["state"]), np.asarray(a_norm.std["state"]), rtol=0.1),
          "(the two runs' state statistics differ, so the check above can fail)")
    small = {"state": jnp.asarray(rng.normal(size=(64, N_OBS)) * 2.0 + 0.5, jnp.float32),
             "privileged_state": jnp.asarray(rng.normal(size=(64, N_PRIV)) * 0.7 - 0.3, jnp.float32)}
    after = running_statistics.update(norm, small)
    rel = float(np.max(np.abs(np.asarray(after.std["state"]) / np.asarray(a_norm.std["state"]) - 1.0)))
    collapsed = running_statistics.update(norm.replace(summed_variance=jax.tree_util.tree_map(
        jnp.zeros_like, norm.summed_variance)), small)
    rel0 = float(np.max(np.abs(np.asarray(collapsed.std["state"]) / np.asarray(a_norm.std["state"]) - 1.0)))
    check(rel < 0.05 < rel0, f"Brax's running update keeps the actor's std (largest change {rel:.3f}; "
          f"with a zero summed variance {rel0:.2f})")

    # Bad input, the file and the field named.
    refused(check, "another --hidden", lambda: graft_actor(actor, critic, (64, 32), N_OBS, N_ACT, N_PRIV),
            "actor.npz", "w0/b0")
    refused(check, "another action scale",
            lambda: graft_actor(actor, critic, HIDDEN, N_OBS, N_ACT, N_PRIV, action_scale=scale * 1.1),
            "actor.npz", "action_scale", "--action-scale-from")
    refused(check, "another mode", lambda: graft_actor(actor, critic, HIDDEN, N_OBS, N_ACT, N_PRIV, mode="pmg"),
            "actor.npz", "mode")
    refused(check, "a critic of another observation size",
            lambda: graft_actor(actor, critic, HIDDEN, N_OBS, N_ACT, N_PRIV + 4), "params.pkl", "privileged_state")
    bare = os.path.join(tmp, "bare.npz")
    write_actor(bare, a_norm, a_params, scale, drop=("obs_std",))
    refused(check, "an actor.npz without its normaliser", lambda: graft_actor(bare, critic, HIDDEN, N_OBS, N_ACT,
                                                                              N_PRIV), "bare.npz", "obs_std")
    junk = os.path.join(tmp, "junk.pkl")
    with open(junk, "wb") as f:
        pickle.dump({"not": "params"}, f)
    refused(check, "a pickle that is no params.pkl", lambda: graft_actor(actor, junk, HIDDEN, N_OBS, N_ACT, N_PRIV),
            "junk.pkl")
    return net, ppo_losses.PPONetworkParams(policy=policy, value=value), norm


def frozen_checks(check, net, params, norm, rng):
    import jax
    import jax.numpy as jnp
    import numpy as np
    from brax.training.agents.ppo import losses as ppo_losses
    from pmg_train.restore import with_frozen_policy

    def batch(n):
        return {"state": jnp.asarray(rng.normal(size=(n, N_OBS)) * 2.0, jnp.float32),
                "privileged_state": jnp.asarray(rng.normal(size=(n, N_PRIV)), jnp.float32)}

    data, kw = ppo_batch(net, norm, params, batch, N_ACT, rng)
    rk = jax.random.PRNGKey(3)
    frozen = with_frozen_policy(ppo_losses.compute_ppo_loss)
    base, _ = ppo_losses.compute_ppo_loss(params, norm, data, rk, **kw)
    loss, _ = frozen(params, norm, data, rk, **kw)
    check(float(loss) == float(base), f"the frozen loss equals PPO's ({float(loss):.6f})")
    g = jax.grad(lambda p: frozen(p, norm, data, rk, **kw)[0])(params)
    g_open = jax.grad(lambda p: ppo_losses.compute_ppo_loss(p, norm, data, rk, **kw)[0])(params)
    pol = max(float(jnp.max(jnp.abs(x))) for x in jax.tree_util.tree_leaves(g.policy))
    pol_open = max(float(jnp.max(jnp.abs(x))) for x in jax.tree_util.tree_leaves(g_open.policy))
    val = max(float(jnp.max(jnp.abs(x))) for x in jax.tree_util.tree_leaves(g.value))
    check(pol == 0.0 and pol_open > 0.0 and val > 0.0,
          f"gradient: policy {pol:.1e} (unfrozen {pol_open:.1e}), critic {val:.1e}")
    val_open = [np.asarray(x) for x in jax.tree_util.tree_leaves(g_open.value)]
    same = all(np.allclose(np.asarray(a), b, rtol=1e-5, atol=1e-7)
               for a, b in zip(jax.tree_util.tree_leaves(g.value), val_open))
    check(same, "the critic's gradient is PPO's own")


def argument_checks(check):
    sys.path.insert(0, os.path.join(REPO, "training"))
    import train_pmg
    base = ["--out", "/tmp/x", "--timesteps", "1000"]
    args = train_pmg.parse_args(base + ["--restore-actor", "a.npz", "--restore-critic", "p.pkl",
                                        "--critic-warmup-steps", "100"])
    check((args.restore_actor, args.restore_critic, args.critic_warmup_steps) == ("a.npz", "p.pkl", 100),
          "--restore-actor, --restore-critic and --critic-warmup-steps parse")
    check(train_pmg.parse_args(base).critic_warmup_steps == 0, "--critic-warmup-steps is 0 (off) by default")
    bad = [["--restore-actor", "a.npz"], ["--restore-critic", "p.pkl"],
           ["--restore-actor", "a.npz", "--restore-critic", "p.pkl", "--restore", "q.pkl"],
           ["--critic-warmup-steps", "100"], ["--restore", "q.pkl", "--critic-warmup-steps", "1000"],
           ["--restore", "q.pkl", "--critic-warmup-steps", "-1"],
           ["--restore", "q.pkl", "--critic-warmup-steps", "100", "--warmup-steps", "100"]]
    for extra in bad:
        err = io.StringIO()
        try:
            with contextlib.redirect_stderr(err):
                train_pmg.parse_args(base + extra)
            check(False, f"{' '.join(extra)} accepted")
        except SystemExit as e:
            flag = "--critic-warmup-steps" if "--critic-warmup-steps" in extra else "--restore-"
            check(e.code == 2 and flag in err.getvalue(), f"{' '.join(extra)} refused: "
                  f"{err.getvalue().strip().splitlines()[-1]}")


def staging_checks(check, tmp, rng):
    """train_pmg.main with --restore-actor and --critic-warmup-steps, Brax's ppo.train replaced by a recorder (so
    nothing compiles): the first call starts from the graft for the critic warm-up's steps with the frozen loss and
    no evaluations, the second from the first's parameters for the remaining steps with the next seed and the run's
    own loss; progress.jsonl marks the stages, train_config.json names the sources; Brax's loss is its own after."""
    import json
    import numpy as np
    from brax.training.agents.ppo import train as ppo
    net = networks()
    a_norm, a_params = trained_run(net, rng, 4, 1.5, 0.2)
    c_norm, c_params = trained_run(net, rng, 5, 1.0, 0.0)
    ref = os.path.join(REPO, "training/results/fidelity/exploration_noise/N24b/train_config.json")
    with open(ref) as f:
        scale = json.load(f)["action_scale"]
    actor, critic = os.path.join(tmp, "stage_actor.npz"), os.path.join(tmp, "stage_params.pkl")
    write_actor(actor, a_norm, a_params, scale)
    write_params(critic, c_norm, c_params)
    calls, lent = [], {"critic": "warmed up"}
    loss = ppo.ppo_losses.compute_ppo_loss

    def recorder(environment, **kw):
        calls.append({"loss": ppo.ppo_losses.compute_ppo_loss, **kw})
        kw["progress_fn"](kw["num_timesteps"], {"training/policy_loss": 0.5})
        if len(calls) == 1:
            return None, lent, {}
        raise _MainStageReached()

    out = os.path.join(tmp, "staging")
    argv = ["--out", out, "--num-envs", "8", "--batch-size", "8", "--num-minibatches", "2", "--unroll-length", "5",
            "--timesteps", "1000", "--num-evals", "2", "--num-eval-envs", "0", "--episode-length", "20",
            "--hidden", ",".join(map(str, HIDDEN)), "--seed", "7", "--mirror-loss", "0.5",
            "--action-scale-from", ref, "--restore-actor", actor, "--restore-critic", critic,
            "--critic-warmup-steps", "400"]
    reached = main_with_recorded_train(argv, recorder)
    check(reached and len(calls) == 2, f"--critic-warmup-steps: train_pmg.main calls ppo.train twice ({len(calls)})")
    if len(calls) != 2:
        return
    c, m = calls
    w0 = c["restore_params"][1]["params"]["hidden_0"]["kernel"] if c["restore_params"] else None
    check(c["num_timesteps"] == 400 and not c["run_evals"] and w0 is not None and
          np.array_equal(w0, np.asarray(a_params.policy["params"]["hidden_0"]["kernel"])) and
          c["loss"] is not loss and c["loss"].__module__ == "pmg_train.restore",
          f"critic stage: {c['num_timesteps']} steps from the grafted actor, no evaluations, the frozen loss")
    check(m["num_timesteps"] == 600 and m["restore_params"] is lent and m["seed"] == 8 and
          m["loss"].__module__ == "pmg_train.symmetry" and ppo.ppo_losses.compute_ppo_loss is loss,
          f"main stage: the remaining {m['num_timesteps']} steps from the critic stage's parameters, seed {m['seed']}, "
          f"the run's loss (mirror loss), Brax's own loss after")
    stages, tc = run_stages(out)
    check(stages == [("critic", 400), ("main", 1000)] and tc["restore_actor"] == actor and
          tc["restore_critic"] == critic and tc["critic_warmup_steps"] == 400,
          f"progress.jsonl (stage, step) {stages}; train_config.json names the actor, the critic and the steps")


def main():
    if os.environ.get(CHILD) != "1":
        relaunch(__file__)
    import numpy as np
    os.chdir(REPO)
    sys.path.insert(0, os.path.join(REPO, "training"))
    check = Checks()
    rng = np.random.default_rng(0)
    with tempfile.TemporaryDirectory() as tmp:
        net, params, norm = graft_checks(check, tmp, rng)
        staging_checks(check, tmp, rng)
    frozen_checks(check, net, params, norm, rng)
    argument_checks(check)
    print(f"{check.passed} passed, {check.failed} failed")
    sys.exit(0 if check.failed == 0 else 1)


if __name__ == "__main__":
    main()
