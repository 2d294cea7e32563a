"""The agent: what decides the gimbal's torque and the vehicle's thrust each control step.

The control step (:mod:`ledsim.agent.step`: gate, supervisor, acquisition, control law,
motor), its parts, and the vehicle's autopilot (:mod:`ledsim.agent.autopilot`: aided
navigation, station keeping, line of sight). It reads the plant (:mod:`ledsim.physics`)
through its sensors and acts on it through its actuators; estimation is
:mod:`observer`'s.
"""
