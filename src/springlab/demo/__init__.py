"""Layer 5, `springlab demo`: the steps of the main job (`steps`), what they share (`state`) and the HTML
report they end in (`report`).
"""
