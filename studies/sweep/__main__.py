import sys

from quadcosim.infra.interrupts import exit_code, leave  # the standard library alone: no window before the try

if __name__ == "__main__":
    try:
        from quadcosim.studies.sweep.command import main

        code = main()
    except KeyboardInterrupt as interrupt:  # Ctrl-C while the packages load: nothing started, nothing to keep
        print("quadcosim sweep: interrupted", file=sys.stderr)
        code = exit_code(interrupt)
    leave(code)
