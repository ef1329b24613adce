#!/usr/bin/env python3
"""The mirror-symmetry maps and loss of pmg_train/symmetry.py (ctest training_symmetry).

Usage: test_symmetry.py [--poses 200] [--seed 0]
Runs in the training environment (.venv-training, like test_smoke_cpu.py: it re-runs itself with that
interpreter; PMG_SKIP_TRAINING_TESTS=1 skips, exit 77). No environment step is compiled. Checks:
1. The leg joint map (the robot config's mirror / mirror_sign) is the G1 model's own symmetry: on random
   leg poses, MuJoCo's forward kinematics of the mirrored pose puts every left leg body where the
   mirror image (y -> -y) of its right partner is, and orients it as M R M (and the other way round).
   The map with hip roll's sign flipped fails this (the check can fail). Every left / right body pair of
   the model (legs and arms) has equal masses, mirrored centres of mass and principal inertias within
   0.1 % (the knee links' differ by 0.06 % in Unitree's model).
2. The actor observation map is the environment's: g1_env.G1PmgEnv.raw_obs of a mirrored state (base
   position and quaternion, linear and angular velocity, all 29 joints, the tracked command, the
   reference, the last action, phase + 1/2) equals the mirror map applied to the observation of the
   original state, on random states (base tilted, joints and velocities random).
3. The loss on a Brax actor (32-32, tanh-normal, observation normalisation): it equals the formula
   computed here from the actor's means (NumPy), is > 0 for a random actor, and minimising it alone
   (Adam, 300 steps on 256 random observations) makes the actor symmetric on 256 fresh observations
   (the loss falls below 5 % of its start).
4. with_mirror_loss around Brax's own compute_ppo_loss on a synthetic batch (the installed Brax's
   signature): the total minus PPO's loss is W x the term, the metrics carry it, W = 0 gives PPO's
   loss exactly, and a negative or NaN weight is refused.
Prints one line per check; exit 0 iff all pass.
"""
import argparse
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
from test_smoke_cpu import CHILD, Checks, relaunch  # noqa: E402

MJCF = "config/robots/g1/g1_29dof_rev_1_0.xml"
ROBOT_YAML = "config/robots/g1/g1.yaml"


def fk_check(check, js, leg_index, leg_sign, n_poses, rng):
    import mujoco
    import numpy as np
    from pmg_train.g1_env import LEG
    m = mujoco.MjModel.from_xml_path(os.path.join(REPO, MJCF))
    d = mujoco.MjData(m)
    hinge = [j for j in range(m.njnt) if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE]
    names = [m.joint(j).name for j in hinge]
    check(names[:LEG] == js.joint_names[:LEG], f"the model's first {LEG} hinges are the robot config's legs")
    adr = [m.jnt_qposadr[j] for j in hinge[:LEG]]
    legs = [b for b in range(m.nbody) if m.body(b).name.startswith("left_") and any(
        k in m.body(b).name for k in ("hip", "knee", "ankle"))]
    pairs = [(b, mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, m.body(b).name.replace("left_", "right_", 1)))
             for b in legs]
    M = np.diag([1.0, -1.0, 1.0])

    def pose(q):
        d.qpos[:] = m.qpos0
        d.qpos[:3] = 0.0
        d.qpos[3:7] = (1.0, 0.0, 0.0, 0.0)
        d.qpos[adr] = q
        mujoco.mj_kinematics(m, d)
        return d.xpos.copy(), d.xmat.reshape(-1, 3, 3).copy()

    lo, hi = js.lower[:LEG], js.upper[:LEG]  # the sides' ranges mirror each other, so q_m stays inside

    def worst(index, sign):
        err = 0.0
        for _ in range(n_poses):
            q = rng.uniform(lo, hi)
            q_m = q[index] * sign
            x, R = pose(q)
            x_m, R_m = pose(q_m)
            for left, right in pairs:
                for a, b in ((left, right), (right, left)):
                    err = max(err, np.abs(x_m[a] - M @ x[b]).max(), np.abs(R_m[a] - M @ R[b] @ M).max())
        return err

    pairs_all = [(b, mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, m.body(b).name.replace("left_", "right_", 1)))
                 for b in range(m.nbody) if m.body(b).name.startswith("left_")]
    mass = max(abs(m.body_mass[a] - m.body_mass[b]) for a, b in pairs_all)
    com = max(np.abs(m.body_ipos[a] * (1, -1, 1) - m.body_ipos[b]).max() for a, b in pairs_all)
    inertia, worst_body = max((np.abs(m.body_inertia[a] - m.body_inertia[b]).max() / m.body_inertia[a].max(),
                               m.body(a).name) for a, b in pairs_all)
    check(all(b >= 0 for _, b in pairs_all) and mass == 0 and com < 1e-9 and inertia < 1e-3,
          f"the model's {len(pairs_all)} left / right body pairs: equal masses, mirrored centres of mass, principal "
          f"inertias within 0.1 % (largest differences {mass:.1e} kg, {com:.1e} m, {100 * inertia:.3f} % at {worst_body})")
    err = worst(leg_index, leg_sign)
    check(len(pairs) == 6 and err < 1e-6, f"forward kinematics of {n_poses} mirrored leg poses: {len(pairs)} body "
          f"pairs, largest position / rotation difference {err:.2e} (< 1e-6)")
    bad_sign = leg_sign.copy()
    bad_sign[[1, 7]] *= -1  # hip roll, both sides
    err_bad = worst(leg_index, bad_sign)
    check(err_bad > 1e-2, f"the same with hip roll's mirror sign flipped: {err_bad:.3f} (> 0.01: the check can fail)")


def obs_check(check, obs_map, leg_map, js, n_states, rng):
    import types
    import jax.numpy as jnp
    import numpy as np
    from pmg_train import g1_env
    from pmg_train.symmetry import COMMAND_SIGN, mirror
    env = g1_env.G1PmgEnv(g1_env.EnvConfig(), os.path.join(REPO, "config/clips/g1"))
    n = len(js.joint_names)
    check(env.js.joint_names == js.joint_names, f"the env's joint space is the robot config's ({n} joints)")
    worst = 0.0
    for _ in range(n_states):
        quat = rng.normal(size=4) * np.array([1.0, 0.2, 0.2, 1.0])
        quat /= np.linalg.norm(quat)
        qpos = np.concatenate([[0.3, 0.2, 0.75], quat, rng.uniform(js.lower, js.upper)])
        qvel = rng.normal(size=6 + n)
        info = {"tracked": rng.normal(size=6), "ref_q": rng.uniform(js.lower, js.upper), "phase": rng.uniform(),
                "last_action": rng.normal(size=g1_env.LEG)}
        w, x, y, z = quat
        qpos_m = np.concatenate([qpos[:3] * (1, -1, 1), [w, -x, y, -z], qpos[7:][js.mirror_index] * js.mirror_sign])
        qvel_m = np.concatenate([qvel[:3] * (1, -1, 1), qvel[3:6] * (-1, 1, -1),
                                 qvel[6:][js.mirror_index] * js.mirror_sign])
        info_m = {"tracked": info["tracked"] * np.array(COMMAND_SIGN),
                  "ref_q": info["ref_q"][js.mirror_index] * js.mirror_sign, "phase": (info["phase"] + 0.5) % 1.0,
                  "last_action": info["last_action"][leg_map[0]] * leg_map[1]}

        def obs(qp, qv, inf):
            data = types.SimpleNamespace(qpos=jnp.asarray(qp, jnp.float32), qvel=jnp.asarray(qv, jnp.float32))
            return np.asarray(jnp.concatenate(env.raw_obs(data, {k: jnp.asarray(v, jnp.float32)
                                                                 for k, v in inf.items()})))

        o, o_m = obs(qpos, qvel, info), obs(qpos_m, qvel_m, info_m)
        worst = max(worst, np.abs(o_m - mirror(o, *obs_map)).max())
    check(worst < 1e-4, f"the env's observation of {n_states} mirrored states equals the mirrored observation: "
          f"largest difference {worst:.2e} (< 1e-4)")


def loss_checks(check, obs_map, act_map, rng):
    import jax
    import jax.numpy as jnp
    import numpy as np
    import optax
    from brax.training.acme import running_statistics, specs
    from brax.training.agents.ppo import losses as ppo_losses
    from brax.training.agents.ppo import networks as ppo_networks
    from pmg_train.symmetry import mirror, mirror_loss, with_mirror_loss
    n_obs, n_act, n_priv = len(obs_map[0]), len(act_map[0]), 90
    net = ppo_networks.make_ppo_networks({"state": (n_obs,), "privileged_state": (n_priv,)}, n_act,
                                         preprocess_observations_fn=running_statistics.normalize,
                                         policy_hidden_layer_sizes=(32, 32), value_hidden_layer_sizes=(32, 32),
                                         policy_obs_key="state", value_obs_key="privileged_state")
    key = jax.random.PRNGKey(int(rng.integers(1 << 30)))
    k1, k2 = jax.random.split(key)
    params = ppo_losses.PPONetworkParams(policy=net.policy_network.init(k1), value=net.value_network.init(k2))

    def batch(n):
        return {"state": jnp.asarray(rng.normal(size=(n, n_obs)) * 2.0, jnp.float32),
                "privileged_state": jnp.asarray(rng.normal(size=(n, n_priv)), jnp.float32)}

    spec = {"state": specs.Array((n_obs,), jnp.float32), "privileged_state": specs.Array((n_priv,), jnp.float32)}
    norm = running_statistics.update(running_statistics.init_state(spec), batch(512))
    obs = batch(256)
    term = float(mirror_loss(net.policy_network.apply, norm, params.policy, obs, "state", obs_map, act_map))
    mu = np.asarray(net.policy_network.apply(norm, params.policy, obs))[:, :n_act]
    obs_m = dict(obs, state=jnp.asarray(mirror(np.asarray(obs["state"]), *obs_map)))
    mu_m = np.asarray(net.policy_network.apply(norm, params.policy, obs_m))[:, :n_act]
    direct = float(np.mean(np.sum((mu_m - mirror(mu, *act_map)) ** 2, axis=1)))
    check(term > 1e-3 and abs(term - direct) <= 1e-5 * max(1.0, direct),
          f"mirror loss of a random actor {term:.5f}, the formula from its means {direct:.5f}")

    opt = optax.adam(3e-3)
    policy = params.policy
    state = opt.init(policy)
    grad_fn = jax.jit(jax.value_and_grad(
        lambda p, o: mirror_loss(net.policy_network.apply, norm, p, o, "state", obs_map, act_map)))
    fresh = batch(256)
    start = float(mirror_loss(net.policy_network.apply, norm, policy, fresh, "state", obs_map, act_map))
    for _ in range(300):
        _, g = grad_fn(policy, obs)
        upd, state = opt.update(g, state)
        policy = optax.apply_updates(policy, upd)
    end = float(mirror_loss(net.policy_network.apply, norm, policy, fresh, "state", obs_map, act_map))
    check(end < 0.05 * start, f"minimised alone, the loss on fresh observations falls {start:.4f} -> {end:.5f} "
          f"(< 5 %)")

    data, kw = ppo_batch(net, norm, params, batch, n_act, rng)
    obs_bt = data.observation
    rk = jax.random.PRNGKey(1)
    base, _ = ppo_losses.compute_ppo_loss(params, norm, data, rk, **kw)
    w = 0.7
    total, metrics = with_mirror_loss(ppo_losses.compute_ppo_loss, w, "state", obs_map, act_map)(
        params, norm, data, rk, **kw)
    t = float(mirror_loss(net.policy_network.apply, norm, params.policy, obs_bt, "state", obs_map, act_map))
    check(abs(float(total) - float(base) - w * t) <= 1e-4 * max(1.0, abs(float(total)))
          and abs(float(metrics["mirror_loss"]) - t) <= 1e-6 * max(1.0, t),
          f"around Brax's PPO loss: {float(total):.4f} = {float(base):.4f} + {w} x {t:.4f}; metrics carry the term")
    zero, _ = with_mirror_loss(ppo_losses.compute_ppo_loss, 0.0, "state", obs_map, act_map)(params, norm, data, rk, **kw)
    check(float(zero) == float(base), f"weight 0: PPO's loss unchanged ({float(zero):.6f})")
    refused = []
    for bad in (-0.1, float("nan")):
        try:
            with_mirror_loss(ppo_losses.compute_ppo_loss, bad, "state", obs_map, act_map)
        except ValueError:
            refused.append(bad)
    check(len(refused) == 2, f"weights -0.1 and nan refused ({refused})")


def ppo_batch(net, norm, params, batch, n_act, rng, B=4, T=5):
    """A synthetic Brax PPO batch (Transition, B x T) for @p net, and compute_ppo_loss's keyword arguments.
    @p batch(n) returns n observations (dict of arrays)."""
    import jax
    import jax.numpy as jnp
    from brax.training import types as brax_types
    obs_bt = jax.tree_util.tree_map(lambda x: x.reshape(B, T, -1), batch(B * T))
    nxt_bt = jax.tree_util.tree_map(lambda x: x.reshape(B, T, -1), batch(B * T))
    raw = jnp.asarray(rng.normal(size=(B, T, n_act)), jnp.float32)
    data = brax_types.Transition(
        observation=obs_bt, action=jnp.tanh(raw), reward=jnp.asarray(rng.normal(size=(B, T)), jnp.float32),
        discount=jnp.ones((B, T)), next_observation=nxt_bt,
        extras={"state_extras": {"truncation": jnp.zeros((B, T))},
                "policy_extras": {"raw_action": raw, "log_prob": jnp.asarray(rng.normal(size=(B, T)) - 10.0,
                                                                              jnp.float32),
                                  "distribution_params": net.policy_network.apply(norm, params.policy, obs_bt)}})
    kw = dict(ppo_network=net, entropy_cost=5e-3, discounting=0.97, reward_scaling=1.0, gae_lambda=0.95,
              clipping_epsilon=0.2, normalize_advantage=True)
    return data, kw


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--poses", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    if os.environ.get(CHILD) != "1":
        relaunch(__file__)
    import numpy as np
    os.chdir(REPO)
    sys.path.insert(0, os.path.join(REPO, "training"))
    from pmg_train import g1_env
    from pmg_train import pmg_generator as pg
    from pmg_train.symmetry import actor_obs_mirror, leg_mirror

    check = Checks()
    rng = np.random.default_rng(args.seed)
    js = pg.joint_space_from_robot_yaml(os.path.join(REPO, ROBOT_YAML))
    leg_index, leg_sign = leg_mirror(js.mirror_index, js.mirror_sign, g1_env.LEG)
    obs_map = actor_obs_mirror(g1_env.OBS_TERMS, leg_index, leg_sign)
    act_map = (leg_index, leg_sign.astype(np.float32))
    n_obs = sum(s for _, s, _ in g1_env.OBS_TERMS)
    check(sorted(obs_map[0].tolist()) == list(range(n_obs))
          and np.array_equal(mirror_twice := obs_map[1][obs_map[0]] * obs_map[1], np.ones(n_obs))
          and np.array_equal(obs_map[0][obs_map[0]], np.arange(n_obs)),
          f"the observation map is a signed permutation of the {n_obs} terms and its own inverse "
          f"({int(mirror_twice.sum())} of {n_obs})")
    try:
        actor_obs_mirror([("base_ang_vel_B", 3, 0.25), ("foot_forces", 2, 1.0)], leg_index, leg_sign)
        check(False, "a term with no mirror rule accepted")
    except ValueError as e:
        check("foot_forces" in str(e), f"a term with no mirror rule refused: {e}")
    fk_check(check, js, leg_index, leg_sign, args.poses, rng)
    obs_check(check, obs_map, act_map, js, 20, rng)
    loss_checks(check, obs_map, act_map, rng)
    print(f"{check.passed} passed, {check.failed} failed")
    sys.exit(0 if check.failed == 0 else 1)


if __name__ == "__main__":
    main()
