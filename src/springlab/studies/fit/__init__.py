"""Fitting a scene to a measurement (`springlab fit`): the record (`data`), what a scene can identify
(`models`), where the motion starts (`release`), the optimization (`engine`), multi-starts (`starts`), the result
(`results`) and the entry point (`fit`).
"""
