"""What a scene can do for the studies, declared on its `Scene` and read by them (a study never names a scene).

Each capability is a small frozen data object, with hooks where a scene's own physics must answer
(implemented in the scene's folder); the studies hold the general machinery and read only these. One
study's contract is one module:

* `fit`: how `springlab fit` identifies the scene from a record (`Scene.fit`);
* `oscillator`: the textbook's one-mode mass-spring-damper of `springlab stability` (`Scene.oscillator`);
* `design`: the design question and its hooks (`Scene.design`, springlab.studies.design);
* `friction`: exact dry-friction cases and MuJoCo's friction settings (`Scene.dry_friction`);
* `refine`: the model's size as a parameter (`Scene.refinable`, springlab.studies.refine);
* `figure`: the panels of the scene's own figure of a run (`Scene.figure`);
* `frequency`: the default input and response of its frequency response (`Scene.frequency`);
* `interactive`: the scenarios that run in the browser (`Scene.interactive`);
* `random_load`: a scenario under a seeded stationary random load and its exact RMS (`Scene.random_load`,
  springlab.studies.random_load and springlab.studies.rms_settings);
* `drawing`: what the videos, the viewer and the pages draw for a case beyond the model's geoms (`Scene.drawing`);
* `case`: what a capability hook reads of the case it is given (`CaseView`).

"""
