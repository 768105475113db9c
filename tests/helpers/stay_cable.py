"""The stay cable the wind tests share (tests/scenes/stay_cable/test_stay_cable_scene.py and the notebook view of
its results in tests/results/test_display.py): the same nine-node cable written once."""

#: a small cable with a short memory for the records: 9 nodes, the damper at node 1, 1 % intrinsic damping
WINDY = {"n_elements": 9, "damper_position": 30.0, "damper_coefficient": 4e4, "structural_damping_ratio": 0.01}
