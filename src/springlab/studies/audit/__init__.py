"""The audit of any MJCF model (`springlab audit`): `audit` (the orchestration, in named steps) reads the
options (`options`), loads the model (`source`) and holds it at its operating point (springlab.exact.
model_at_point); it starts its runs (`start`), finds the stability limits per integrator (`predict`, `limits`),
sweeps error against cost (`sweep`), ships chunks to the executor (`ship`), and returns an `Audit` (`results`,
made of `parts`) whose words are `text`.
"""
