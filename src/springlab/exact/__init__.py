"""Layer 1, exact answers: closed forms (`analytic`), linear systems by the matrix exponential (`linear`),
kinematics (`polynomials`), MuJoCo's own linearization (`linearize`), events between samples (`events`),
the integrators' exact stability limits (`limits`), the forced Duffing oscillator's first-order harmonic
balance with its derived error bound (`harmonic_balance`), and control of a flexible drive: input shapers
and their residual vibration (`shaping`), the exact ring-down after a move (`positioning`), sampled-data
feedback (`sampled_loop`) and the resonance test's fit (`resonance`); the taut cable with its damper (`cable`)
and the stationary response to white noise with the scatter of an estimated RMS (`random_vibration`).
"""
