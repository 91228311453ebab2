"""The flight: the closed loop of thesis 7.2 (:mod:`.closed_loop`), ``Flight(plant, manager,
mission).run()`` (:mod:`.flight`), the manager's settings (:mod:`.manager_settings`), re-planning
(:mod:`.replanning`), open-loop plans (:mod:`.open_loop`) and the record (:mod:`.flight_result`).
"""
