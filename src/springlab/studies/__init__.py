"""Layer 3, studies: many runs answering one question. The trade-off of error against cost (`tradeoff`),
stability (`stability`, `extremes`), `integrator='auto'` (`auto`, which is `springlab.run`), parameter
sweeps (`sweeps`), families of runs for figures (`families`), the audit of any MJCF (`audit/`), fitting a
measurement (`fit/`), the design study (`design/`); `executor` runs their chunks locally or on Dask.
A study never names a scene: it reads what a scene declares (`springlab.scenes.base.Scene`).
"""
