"""The audit of any MJCF model (`springlab audit`): modes at the operating point, stability limits per
integrator (`limits`), error against cost (`sweep`), chunks shipped to the executor (`ship`), the result (`audit`).
"""
