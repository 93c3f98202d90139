"""``python -m quadcosim.studies.sweep``: the same as ``quadcosim sweep``."""

from quadcosim.infra.command import Command, program  # the standard library alone: no window before the try


def _sweep() -> int:
    from quadcosim.studies.sweep.command import main  # Ctrl-C while the packages load: nothing started

    return main()


if __name__ == "__main__":
    program(Command("quadcosim sweep").run, _sweep)  # Ctrl-C while the packages load: said, 130
