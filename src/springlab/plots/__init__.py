"""Layer 4, plots: matplotlib figures of results they are given (runs, families, trade-offs, stability,
sweeps, audits, fits, design studies). Nothing here simulates.
"""
