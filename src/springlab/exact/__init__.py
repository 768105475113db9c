"""Layer 1, exact answers: closed forms (`analytic`), linear systems by the matrix exponential (`linear`),
kinematics (`polynomials`), MuJoCo's own linearization (`linearize`), events between samples (`events`),
the integrators' exact stability limits (`limits`) and the forced Duffing oscillator's first-order harmonic
balance with its derived error bound (`harmonic_balance`), the taut cable with its damper (`cable`) and the
stationary response to white noise with the scatter of an estimated RMS (`random_vibration`).
"""
