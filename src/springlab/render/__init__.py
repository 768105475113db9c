"""Layer 4, render: off-screen videos of finished runs (`video`, `media`), drawn with MuJoCo's renderer on
EGL (`gl`), framed (`framing`), annotated (`drawings`, `text`, `scale`) and encoded (`sink`); `stage` arranges a
model for watching, for the videos and the live viewer (springlab.cli.view) alike. Nothing here simulates.
"""
