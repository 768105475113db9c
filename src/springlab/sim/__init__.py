"""Layer 1, simulation: headless MuJoCo runs (`simulate`), batched and threaded runs (`batch`), MJCF-native
input generators (`exciter`) and where the model files are (`model_files`). Knows no scene.
"""
