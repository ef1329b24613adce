"""Left-right mirror symmetry of the leg actor, and the mirror-symmetry loss (`train_pmg.py --mirror-loss W`).

The G1 is symmetric about its sagittal plane, the base frame's x-z plane (M = diag(1, -1, 1)). A policy
that walks left should, seen in a mirror, walk right: pi(M_o o) = M_a pi(o). PPO does not know this,
so it learns each side's behaviour from its own samples. The mirror-symmetry loss (Yu, Turk, Liu,
"Learning Symmetric and Low-Energy Locomotion", SIGGRAPH 2018, eq. 4) adds to PPO's loss

    W * mean over the batch of || mu(M_o o) - M_a mu(o) ||^2

where mu is the actor's mean action before the tanh squashing (tanh is odd, so M_a commutes with it),
and o the raw observation (the network normalises it itself). It touches no environment, reward or
the critic; W = 0 leaves PPO's loss exactly as it was.

Maps (signed permutations: x_mirrored[i] = sign[i] * x[index[i]]):
- joints: the robot config's `mirror` / `mirror_sign` (pmg_generator.JointSpace: mirror_index,
  mirror_sign; the same map mirrors clips, pmg::mirrorClip). The actor's 12 leg joints map onto
  themselves (hip roll and yaw, ankle roll change sign);
- actor observation, term by term (g1_env.OBS_TERMS):
  base_ang_vel_B (omega_x, omega_y, omega_z) -> (-, +, -) (an axial vector, base frame);
  projected_gravity_B (g_x, g_y, g_z) -> (+, -, +);
  command (v_x, v_y, omega, pitch, roll, height) -> (+, -, -, +, -, +);
  joint_pos_rel, joint_vel, last_action, pmg_ref_q_rel: the leg joint map;
  pmg_phase (sin 2 pi phase, cos 2 pi phase) -> (-, -): half a gait cycle later, because every clip is
  aligned on the left touchdown (pmg_generator.align_on_left_touchdown), so the mirrored gait's left
  touchdown is the original's right one. That is exact for a gait whose right touchdown comes half a
  cycle after its left; the shipped side-step's comes 0.42 of a cycle after it
  (training/reference_symmetry.py --scan-shift). For the static clips phase does not matter.
- action (leg joint position offsets): the leg joint map.

ctest training_symmetry (training/tests/test_symmetry.py) checks the joint map against MuJoCo's forward
kinematics of the G1 model, the observation map against the environment's own observation of a
mirrored state, and the loss against Brax's PPO loss.
"""
import numpy as np

COMMAND_SIGN = (1.0, -1.0, -1.0, 1.0, -1.0, 1.0)  # v_x, v_y, omega, pitch, roll, height
_VECTOR_SIGN = {"base_ang_vel_B": (-1.0, 1.0, -1.0), "projected_gravity_B": (1.0, -1.0, 1.0),
                "command": COMMAND_SIGN, "pmg_phase": (-1.0, -1.0)}
_LEG_TERMS = ("joint_pos_rel", "joint_vel", "last_action", "pmg_ref_q_rel")


def leg_mirror(mirror_index, mirror_sign, n_leg):
    """(index, sign) of the first @p n_leg joints (robot order) from the robot config's full joint map.

    Raises ValueError if a leg joint's mirror is not a leg joint, or the map is not an involution."""
    index = np.asarray(mirror_index, int)
    sign = np.asarray(mirror_sign, float)
    leg_index, leg_sign = index[:n_leg], sign[:n_leg]
    if np.any(leg_index >= n_leg) or np.any(leg_index < 0):
        raise ValueError(f"leg joints mirror onto joints {sorted(set(leg_index[leg_index >= n_leg].tolist()))} "
                         f"outside the first {n_leg}: expected the legs to map onto themselves")
    if not (np.array_equal(leg_index[leg_index], np.arange(n_leg))
            and np.array_equal(leg_sign[leg_index] * leg_sign, np.ones(n_leg))):
        raise ValueError("the leg mirror map is not an involution (mirroring twice must give the identity)")
    return leg_index, leg_sign


def actor_obs_mirror(obs_terms, leg_index, leg_sign):
    """(index, sign) over the actor observation laid out as @p obs_terms ((name, size, scale) list).

    Raises ValueError for a term it has no mirror rule for."""
    index, sign, start = [], [], 0
    for name, size, _ in obs_terms:
        if name in _VECTOR_SIGN and len(_VECTOR_SIGN[name]) == size:
            index += list(range(start, start + size))
            sign += list(_VECTOR_SIGN[name])
        elif name in _LEG_TERMS and size == len(leg_index):
            index += [start + int(i) for i in leg_index]
            sign += list(leg_sign)
        else:
            raise ValueError(f"observation term {name!r} (size {size}): no mirror rule; expected one of "
                             f"{sorted(_VECTOR_SIGN) + list(_LEG_TERMS)} with its size")
        start += size
    return np.asarray(index, int), np.asarray(sign, np.float32)


def actor_maps(js, obs_terms, n_leg):
    """((obs index, obs sign), (action index, action sign)) of a leg actor: @p js a
    pmg_generator.JointSpace (the robot config's mirror map), @p obs_terms its observation layout,
    the actions the first @p n_leg joints."""
    leg = leg_mirror(js.mirror_index, js.mirror_sign, n_leg)
    return actor_obs_mirror(obs_terms, *leg), (leg[0], leg[1].astype(np.float32))


def env_maps(env):
    """actor_maps of a g1_env.G1PmgEnv's actor."""
    from pmg_train.g1_env import LEG, OBS_TERMS
    if env.action_size != LEG:
        raise ValueError(f"action size {env.action_size}: expected the {LEG} leg joints")
    return actor_maps(env.js, OBS_TERMS, LEG)


def mirror(x, index, sign):
    """The signed permutation x[..., index] * sign (NumPy or JAX arrays)."""
    return x[..., index] * sign


def mirror_loss(policy_apply, normalizer_params, policy_params, observation, obs_key, obs_map, act_map):
    """mean_batch || mu(M_o o) - M_a mu(o) ||^2 for a Brax tanh-normal actor.

    policy_apply(normalizer_params, policy_params, observation) -> logits (..., 2 n_act), the first n_act
    the pre-tanh mean; @p observation a dict holding the actor's raw observation under @p obs_key."""
    import jax.numpy as jnp
    obs_index, obs_sign = obs_map
    act_index, act_sign = act_map
    mirrored = dict(observation)
    mirrored[obs_key] = mirror(observation[obs_key], obs_index, jnp.asarray(obs_sign))
    n = len(act_index)
    mu = policy_apply(normalizer_params, policy_params, observation)[..., :n]
    mu_m = policy_apply(normalizer_params, policy_params, mirrored)[..., :n]
    err = mu_m - mirror(mu, act_index, jnp.asarray(act_sign))
    return jnp.mean(jnp.sum(err * err, axis=-1))


def with_mirror_loss(compute_ppo_loss, weight, obs_key, obs_map, act_map):
    """Brax's compute_ppo_loss plus weight x mirror_loss on the batch's observations.

    Same signature and return (loss, metrics) as brax.training.agents.ppo.losses.compute_ppo_loss; the
    metrics gain "mirror_loss" (the unweighted term)."""
    if not (np.isfinite(weight) and weight >= 0):
        raise ValueError(f"mirror loss weight {weight}: expected a finite value >= 0")

    def loss(params, normalizer_params, data, rng, ppo_network, **kwargs):
        total, metrics = compute_ppo_loss(params, normalizer_params, data, rng, ppo_network, **kwargs)
        term = mirror_loss(ppo_network.policy_network.apply, normalizer_params, params.policy, data.observation,
                           obs_key, obs_map, act_map)
        metrics = dict(metrics)
        metrics["mirror_loss"] = term
        return total + weight * term, metrics

    return loss
