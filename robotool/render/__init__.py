"""Pictures and videos of scenes and rollouts, drawn headless with MuJoCo's renderer.

- :mod:`robotool.render.picture_model` — what pictures show: the task's model with colours, a grid and goal markers.
- :mod:`robotool.render.camera` — a fixed camera per embodiment that keeps given states in view.
- :mod:`robotool.render.painter` — ``Painter``: draw a state, project points, label the objects.
- :mod:`robotool.render.overlay` — labels, titles and captions drawn over frames (PIL).
- :mod:`robotool.render.still` — ``render_scene`` (a task at its start) and ``render_state`` (a world at its end).
- :mod:`robotool.render.video` — recorded states -> captioned frames -> MP4 (PyAV).
- :mod:`robotool.render.run_videos` — videos of program runs (record chosen worlds, write one MP4 each).
- :mod:`robotool.render.top_view` — a top-down plan of a rollout (matplotlib, no OpenGL).

States are recorded during a run by :class:`robotool.sim.recorder.StateRecorder`, only when asked for.
"""
