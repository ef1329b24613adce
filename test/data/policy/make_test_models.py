#!/usr/bin/env python3
"""Writes the small ONNX models used by test/policy (committed next to this script).

Run from the repository root:  python3 test/data/policy/make_test_models.py
Needs numpy, pyyaml and the `onnx` pip package (scripts/setup.sh installs them). The robot data
(joint order, default pose, PD gains) come from config/robots/g1/g1.yaml so the "good" models
match the robot configuration; every "bad_*" model breaks exactly one contract field.
Reference observation->action pairs are computed with a float32 NumPy forward pass, which the
C++ runner must reproduce through ONNX Runtime to float tolerance.
"""
import copy
import os
import sys

import numpy as np
import yaml

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "training"))
from pmg_train.contract import make_contract, mlp_forward, mlp_graph, obs_dim, save_onnx  # noqa: E402

OUT = os.path.dirname(os.path.abspath(__file__))
CONTROL_PERIOD = 0.01  # s, the controller's 100 Hz loop
PMG = {"enabled": True, "gco": False, "gait_period": 0.8}

with open(os.path.join(ROOT, "config/robots/g1/g1.yaml")) as f:
    robot = yaml.safe_load(f)
joints = robot["joints"]
names = [j["name"] for j in joints]
default = np.array([j["default"] for j in joints], dtype=np.float64)
kp = np.array([j["kp"] for j in joints], dtype=np.float64)
kd = np.array([j["kd"] for j in joints], dtype=np.float64)
legs = names[:12]
waist = names[12:15]


def terms_for(n_act):
    return [("base_ang_vel_B", 3, 0.25), ("projected_gravity_B", 3, 1.0),
            ("command", 6, [2.0, 2.0, 0.25, 1.0, 1.0, 1.0]), ("joint_pos_rel", n_act, 1.0),
            ("joint_vel", n_act, 0.05), ("last_action", n_act, 1.0), ("pmg_ref_q_rel", n_act, 1.0),
            ("pmg_phase", 2, 1.0)]


def build(seed, actuated, controls_waist, history, nan_model=False, hidden=(32,)):
    rng = np.random.default_rng(seed)
    n_act = len(actuated)
    idx = [names.index(a) for a in actuated]
    proto = make_contract(robot=robot["robot"]["name"], joint_names=names, actuated_joints=actuated,
                          controls_waist=controls_waist, control_period=CONTROL_PERIOD,
                          default_pose=default, kp=kp, kd=kd, action_scale=np.full(n_act, 0.25),
                          action_offset=default[idx], action_clip=10.0, obs_terms=terms_for(n_act),
                          history_length=history, obs_clip=100.0, pmg=PMG, reference_pairs=[])
    d_in = obs_dim(proto)
    dims = [d_in, *hidden, n_act]
    layers = [(rng.normal(0, 1 / np.sqrt(a), (a, b)), rng.normal(0, 0.1, b)) for a, b in zip(dims[:-1], dims[1:])]
    layers = [(w.astype(np.float32), b.astype(np.float32)) for w, b in layers]
    pairs = []
    for _ in range(5):
        o = rng.uniform(-1, 1, d_in).astype(np.float32)
        o[0] = abs(o[0]) + 0.01  # keep obs[0] > 0 so the NaN model is finite on its references
        pairs.append((o, mlp_forward(layers, o[None, :])[0]))
    proto["reference_pairs"] = [{"obs": [float(v) for v in o], "action": [float(v) for v in a]}
                                for o, a in pairs]
    graph = mlp_graph(layers, d_in, n_act, nan_on_negative_first_input=nan_model)
    return graph, proto, layers


def main():
    g, c, _ = build(1, legs, False, 1)
    save_onnx(os.path.join(OUT, "g1_legs_ok.onnx"), g, c)
    g2, c2, _ = build(2, legs + waist, True, 3)
    save_onnx(os.path.join(OUT, "g1_legs_waist_hist3_ok.onnx"), g2, c2)

    def bad(name, mutate, graph=g, base=c):
        cc = copy.deepcopy(base)
        mutate(cc)
        save_onnx(os.path.join(OUT, f"bad_{name}.onnx"), graph, cc)

    def swap(cc):
        cc["joint_names"][3], cc["joint_names"][4] = cc["joint_names"][4], cc["joint_names"][3]
    bad("joint_order", swap)
    bad("kp", lambda cc: cc["kp"].__setitem__(3, 100.0))
    bad("kd", lambda cc: cc["kd"].__setitem__(0, 1.0))
    bad("default_pose", lambda cc: cc["default_pose"].__setitem__(3, 0.5))
    bad("control_period", lambda cc: cc.__setitem__("control_period", 0.02))
    bad("reference", lambda cc: cc["reference_pairs"][2]["action"].__setitem__(5, cc["reference_pairs"][2]["action"][5] + 1e-2))
    def grow_obs(cc):  # self-consistent contract describing one more input than the graph has
        cc["observation"]["terms"][0]["size"] = 4
        for pair in cc["reference_pairs"]:
            pair["obs"].append(0.0)
    bad("obs_layout", grow_obs)
    bad("actuated_waist", lambda cc: cc["actuated_joints"].__setitem__(11, "waist_yaw_joint"))
    bad("unknown_joint", lambda cc: cc["actuated_joints"].__setitem__(0, "left_hip_pitch"))
    bad("pmg_gco", lambda cc: cc["pmg"].__setitem__("gco", True))
    bad("action_scale_size", lambda cc: cc["action"]["scale"].pop())
    bad("version", lambda cc: cc.__setitem__("version", 99))
    save_onnx(os.path.join(OUT, "bad_no_contract.onnx"), g, c, drop_contract=True)
    save_onnx(os.path.join(OUT, "bad_yaml.onnx"), g, c,
              extra_metadata={"pmg.contract": "version: 1\njoint_names: [a, b\n"})
    gn, cn, _ = build(1, legs, False, 1, nan_model=True)
    save_onnx(os.path.join(OUT, "nan_output.onnx"), gn, cn)
    # A graph with an op the native backend does not implement (Softplus): ORT runs it, the
    # native backend must refuse it at load, naming the op.
    import onnx
    from onnx import helper
    gs = copy.deepcopy(g)
    out = gs.output[0].name
    for node in gs.node:
        if out in node.output:
            node.output[0] = "pre_softplus"
    gs.node.append(helper.make_node("Softplus", ["pre_softplus"], [out]))
    cs = copy.deepcopy(c)
    _, _, layers = build(1, legs, False, 1)
    for pair in cs["reference_pairs"]:
        a = np.asarray(pair["action"], np.float32)
        pair["action"] = [float(v) for v in np.log1p(np.exp(a)).astype(np.float32)]
    save_onnx(os.path.join(OUT, "softplus_ok_for_ort.onnx"), gs, cs)
    # Actor of the usual deployed size (512-256-128 ELU/tanh MLP) for bench/policy.
    gb, cb, _ = build(3, legs, False, 1, hidden=(512, 256, 128))
    save_onnx(os.path.join(OUT, "g1_legs_512_256_128.onnx"), gb, cb)
    print("wrote models to", OUT)


if __name__ == "__main__":
    main()
