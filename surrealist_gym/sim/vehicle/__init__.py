"""The vehicle and what moves it: airframe parameters and presets (:mod:`.airframe`), PX4's attitude, rate and
position controllers (:mod:`.control`), the rigid body and motors (:mod:`.rigid_body`), and the two physics that fly
it: compiled (:mod:`.compiled_physics`, with the scene's closed-form geometry in :mod:`.geometry_kernels`) and
PyBullet (:mod:`.world`, quietened by :mod:`.pybullet_quiet`)."""
