"""Layer 2, one run: a scene's scenario at one setting, compared with its exact answer (`run`: `Result`,
`run_scenario`, `validate_scenarios`, `write_run`), and the error estimate behind every verdict (`compare`).
"""
