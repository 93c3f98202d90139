"""The co-simulation orchestrator: blocks, connections, a fixed-step master, results."""

from orchestrator.blocks import Block, Constant, FMUBlock, Table
from orchestrator.errors import AlgebraicLoopError, RunInterrupted, SimulationError
from orchestrator.faults import Fault
from orchestrator.fmu import FMUError, FMUInstance
from orchestrator.result import Result
from orchestrator.system import System

__all__ = ["AlgebraicLoopError", "Block", "Constant", "FMUBlock", "FMUError", "FMUInstance", "Fault",
           "Result", "RunInterrupted", "SimulationError", "System", "Table"]
