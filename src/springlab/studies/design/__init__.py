"""The design study (`springlab design`): a scene's design question over a grid of its properties
(`study`), the batched runs (`moves`) and variance-based sensitivities (`sobol`).
"""
