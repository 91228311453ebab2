"""The monitor role: fault detection (:mod:`.monitor`, :mod:`.detector`, :mod:`.innovation_detector`),
identification (:mod:`.fault_identification`) and the sensor watches (:mod:`.sensor_watch`,
:mod:`.input_watch`).
"""
