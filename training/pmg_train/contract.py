"""Policy contract: the YAML document stored in an exported ONNX actor's metadata.

The C++ runner (include/pmg/policy/contract.hpp) parses exactly this document from the ONNX
model's custom_metadata_map key ``pmg.contract`` and refuses to start on any mismatch with the
robot configuration. docs/policy.md documents every field. Units: SI (rad, s, N*m/rad, N*m*s/rad).
"""
from __future__ import annotations

import numpy as np
import onnx
import yaml
from onnx import TensorProto, helper, numpy_helper

CONTRACT_KEY = "pmg.contract"
CONTRACT_VERSION = 1
INPUT_NAME = "obs"
OUTPUT_NAME = "action"


def _floats(x):
    return [float(v) for v in np.asarray(x, dtype=np.float64).ravel()]


def make_contract(*, robot, joint_names, actuated_joints, controls_waist, control_period,
                  default_pose, kp, kd, action_scale, action_offset, action_clip,
                  obs_terms, history_length, obs_clip, pmg, reference_pairs):
    """Builds the contract dict.

    obs_terms: list of (name, size, scale) with scale a float or a list of `size` floats.
    reference_pairs: list of (obs, action) float32 arrays of shape (obs_dim,), (n_act,).
    pmg: flat dict of PMG/GCO settings (str -> bool/float/str).
    """
    terms = []
    for name, size, scale in obs_terms:
        s = float(scale) if np.isscalar(scale) else _floats(scale)
        terms.append({"name": name, "size": int(size), "scale": s})
    return {
        "version": CONTRACT_VERSION,
        "robot": robot,
        "joint_names": list(joint_names),
        "actuated_joints": list(actuated_joints),
        "controls_waist": bool(controls_waist),
        "control_period": float(control_period),
        "default_pose": _floats(default_pose),
        "kp": _floats(kp),
        "kd": _floats(kd),
        "action": {"scale": _floats(action_scale), "offset": _floats(action_offset),
                   "clip": float(action_clip)},
        "observation": {"history_length": int(history_length), "history_order": "newest_first",
                        "clip": float(obs_clip), "terms": terms},
        "pmg": dict(pmg),
        "reference_pairs": [{"obs": _floats(o), "action": _floats(a)} for o, a in reference_pairs],
    }


def obs_dim(contract):
    per_frame = sum(t["size"] for t in contract["observation"]["terms"])
    return per_frame * contract["observation"]["history_length"]


def mlp_forward(layers, x, final_activation=None):
    """float32 forward pass of an MLP with tanh hidden activations (the exported graph)."""
    h = np.asarray(x, dtype=np.float32)
    for i, (w, b) in enumerate(layers):
        h = (h @ w.astype(np.float32) + b.astype(np.float32)).astype(np.float32)
        if i + 1 < len(layers):
            h = np.tanh(h).astype(np.float32)
    return h


def mlp_graph(layers, in_dim, out_dim, name="pmg_actor", nan_on_negative_first_input=False):
    """ONNX graph: obs[1,in_dim] -> (Gemm -> Tanh)* -> Gemm -> action[1,out_dim].

    nan_on_negative_first_input adds 0*sqrt(obs[0,0]) to every output (test models only): the
    action becomes NaN whenever obs[0,0] < 0, which lets tests exercise the NaN guard.
    """
    nodes, inits = [], []
    cur = INPUT_NAME
    for i, (w, b) in enumerate(layers):
        wn, bn = f"w{i}", f"b{i}"
        inits += [numpy_helper.from_array(w.astype(np.float32), wn),
                  numpy_helper.from_array(b.astype(np.float32).reshape(1, -1), bn)]
        last = i + 1 == len(layers)
        lin = (OUTPUT_NAME if not nan_on_negative_first_input else "raw") if last else f"lin{i}"
        nodes.append(helper.make_node("Gemm", [cur, wn, bn], [lin]))
        cur = lin
        if not last:
            nodes.append(helper.make_node("Tanh", [lin], [f"h{i}"]))
            cur = f"h{i}"
    if nan_on_negative_first_input:
        inits += [numpy_helper.from_array(np.array([0, 0], dtype=np.int64), "s0"),
                  numpy_helper.from_array(np.array([1, 1], dtype=np.int64), "s1"),
                  numpy_helper.from_array(np.zeros((1, 1), np.float32), "zero")]
        nodes += [helper.make_node("Slice", [INPUT_NAME, "s0", "s1"], ["x0"]),
                  helper.make_node("Sqrt", ["x0"], ["sx0"]),
                  helper.make_node("Mul", ["sx0", "zero"], ["nan_term"]),
                  helper.make_node("Add", [cur, "nan_term"], [OUTPUT_NAME])]
    graph = helper.make_graph(
        nodes, name,
        [helper.make_tensor_value_info(INPUT_NAME, TensorProto.FLOAT, [1, in_dim])],
        [helper.make_tensor_value_info(OUTPUT_NAME, TensorProto.FLOAT, [1, out_dim])],
        initializer=inits)
    return graph


def save_onnx(path, graph, contract, extra_metadata=None, drop_contract=False):
    model = helper.make_model(graph, producer_name="pmg-training",
                              opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    meta = {} if drop_contract else {CONTRACT_KEY: yaml.safe_dump(contract, sort_keys=False,
                                                                   default_flow_style=None,
                                                                   width=1 << 20)}
    meta.update(extra_metadata or {})
    for k, v in meta.items():
        entry = model.metadata_props.add()
        entry.key, entry.value = k, v
    onnx.checker.check_model(model)
    onnx.save(model, path)


# ---- exported actor (Brax PPO policy: normaliser -> MLP(swish) -> loc -> tanh) ----------------

def actor_forward(mean, std, layers, n_act, x):
    """float32 NumPy forward pass identical to actor_graph()."""
    h = ((np.asarray(x, np.float32) - mean.astype(np.float32)) / std.astype(np.float32)).astype(np.float32)
    for i, (w, b) in enumerate(layers):
        h = (h @ w.astype(np.float32) + b.astype(np.float32)).astype(np.float32)
        if i + 1 < len(layers):
            h = (h * (1.0 / (1.0 + np.exp(-h)))).astype(np.float32)
    return np.tanh(h[..., :n_act]).astype(np.float32)


def actor_graph(mean, std, layers, n_act, name="pmg_actor"):
    """ONNX graph of a Brax PPO actor: obs[1,n_obs] -> action[1,n_act] (deterministic, tanh)."""
    n_obs = mean.shape[0]
    inits = [numpy_helper.from_array(mean.astype(np.float32).reshape(1, -1), "obs_mean"),
             numpy_helper.from_array(std.astype(np.float32).reshape(1, -1), "obs_std"),
             numpy_helper.from_array(np.array([0], np.int64), "sl_start"),
             numpy_helper.from_array(np.array([n_act], np.int64), "sl_end"),
             numpy_helper.from_array(np.array([1], np.int64), "sl_axis")]
    nodes = [helper.make_node("Sub", [INPUT_NAME, "obs_mean"], ["centred"]),
             helper.make_node("Div", ["centred", "obs_std"], ["normalised"])]
    cur = "normalised"
    for i, (w, b) in enumerate(layers):
        inits += [numpy_helper.from_array(w.astype(np.float32), f"w{i}"),
                  numpy_helper.from_array(b.astype(np.float32).reshape(1, -1), f"b{i}")]
        nodes.append(helper.make_node("Gemm", [cur, f"w{i}", f"b{i}"], [f"lin{i}"]))
        cur = f"lin{i}"
        if i + 1 < len(layers):
            nodes += [helper.make_node("Sigmoid", [cur], [f"sig{i}"]),
                      helper.make_node("Mul", [cur, f"sig{i}"], [f"h{i}"])]
            cur = f"h{i}"
    nodes += [helper.make_node("Slice", [cur, "sl_start", "sl_end", "sl_axis"], ["loc"]),
              helper.make_node("Tanh", ["loc"], [OUTPUT_NAME])]
    return helper.make_graph(
        nodes, name, [helper.make_tensor_value_info(INPUT_NAME, TensorProto.FLOAT, [1, n_obs])],
        [helper.make_tensor_value_info(OUTPUT_NAME, TensorProto.FLOAT, [1, n_act])], initializer=inits)


def clips_digest(clip_files):
    """Digest of the clips' joint data, the contract's pmg.clips_digest (equal to the C++
    pmg::clipsDigest, include/pmg/clips/clip_io.hpp): FNV-1a 64-bit over every clip file's clip
    (dynamic and static; consistency_map.yaml and other kinds skipped) in the order of the clips'
    names: the name's bytes, then each q value (row-major) as the int64 floor(q * 1e4 + 0.5) in 8
    little-endian bytes; "fnv1a64:" and 16 hex digits."""
    clips = []
    for path in clip_files:
        with open(path) as f:
            doc = yaml.safe_load(f)
        if not isinstance(doc, dict) or doc.get("kind") not in ("dynamic", "static"):
            continue
        clips.append((str(doc["name"]), np.asarray(doc["q"], np.float64)))
    if not clips:
        raise ValueError(f"clips_digest: no clip among {clip_files}")
    clips.sort(key=lambda c: c[0].encode())
    h = 0xcbf29ce484222325
    mask = (1 << 64) - 1

    def feed(data):
        nonlocal h
        for b in data:
            h = ((h ^ b) * 0x100000001b3) & mask

    for name, q in clips:
        feed(name.encode())
        v = np.floor(q * 1e4 + 0.5).astype(np.int64)
        feed(v.astype("<i8").tobytes())
    return f"fnv1a64:{h:016x}"
