"""Layer 2, one run: a scene's scenario at one explicit setting, compared with its exact answer (`run`:
`run_scenario` -> `Result`; `result`: `Result`, `ValidationRow`), and the error estimate and `Verdict` behind every
verdict (`compare`). `springlab.run`, which adds `integrator='auto'`, is a study above (springlab.studies.auto).
"""
