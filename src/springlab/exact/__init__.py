"""Layer 1, exact answers: closed forms (`analytic`), linear systems by the matrix exponential (`linear`),
kinematics (`polynomials`), MuJoCo's own linearization (`linearize`), events between samples (`events`) and
the integrators' exact stability limits (`limits`).
"""
