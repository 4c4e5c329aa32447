"""Running the simulator in real time: clock, fixed-period loop, safety stage, virtual rig.

The loop (:mod:`motosim.rt.loop`) calls the same compiled stack step as the offline simulator
(:mod:`motosim.sim`), driven by a clock (:mod:`motosim.rt.clock`) or by the drive's status
frames, talking to the handlebar
drive over CAN (:mod:`motosim.io.can`), with a safety stage (:mod:`motosim.rt.safety`) as
the last stage before the bus. A virtual rig (:mod:`motosim.rt.rig`) answers the same frames
as a drive, so everything runs and is tested without hardware.
"""
