"""A motor model of a user's own, exported with pythonfmu (not this project's FMU builder).

Four rotors whose speeds follow the ESC commands with a first-order lag,
``d omega_n / dt = (c_n omega_max - omega_n) / tau``, a current proportional to the command,
and no magnetic field. Same variable names and units as the plant's MotorMagnetics for the
signals the plant reads; pythonfmu 0.7 writes no units (the master then takes the block's).
"""

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real

ROTORS = (1, 2, 3, 4)


class FirstOrderMotor(Fmi2Slave):
    author = "a student"
    description = "four rotors, first-order speed response to the ESC command"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.tau = 0.03  # s
        self.omega_max = 1000.0  # rad/s at command 1
        self.current_max = 20.0  # A at command 1
        self.register_variable(Real("tau", causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))
        self.register_variable(Real("omega_max", causality=Fmi2Causality.parameter,
                                    variability=Fmi2Variability.tunable))
        self.register_variable(Real("current_max", causality=Fmi2Causality.parameter,
                                    variability=Fmi2Variability.tunable))
        for n in ROTORS:
            for name, causality in ((f"c{n}", Fmi2Causality.input), (f"omega_r{n}", Fmi2Causality.output),
                                    (f"domega_r{n}", Fmi2Causality.output), (f"i{n}", Fmi2Causality.output)):
                setattr(self, name, 0.0)
                self.register_variable(Real(name, causality=causality))
        for axis in "xyz":
            setattr(self, f"b_d_{axis}", 0.0)
            self.register_variable(Real(f"b_d_{axis}", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        for n in ROTORS:
            command = min(max(getattr(self, f"c{n}"), 0.0), 1.0)
            omega = getattr(self, f"omega_r{n}")
            rate = (command * self.omega_max - omega) / self.tau
            setattr(self, f"domega_r{n}", rate)
            setattr(self, f"omega_r{n}", omega + rate * step_size)
            setattr(self, f"i{n}", command * self.current_max)
        return True
