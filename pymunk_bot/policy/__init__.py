"""Trained navigation policies: what a policy sees and how its action drives a robot
(``io``), its observation written in one compiled pass (``observation_rows``), and policy
files (``files``: a plain MLP in .npz, or ONNX)."""
