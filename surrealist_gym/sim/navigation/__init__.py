"""PX4's navigator and its flight task: the mission phases and setpoints, as readable Python (:mod:`.navigator`,
:mod:`.flight_task`, which the PyBullet run loop flies) and as the kernels of the compiled loop
(:mod:`.navigator_kernels`, :mod:`.flight_task_kernels`, their state in :mod:`.navigator_state`)."""
