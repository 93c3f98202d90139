import sys

try:
    from scenarios.sweep.command import main
except KeyboardInterrupt:  # Ctrl-C while the packages load: nothing started, nothing to keep
    print("quadcosim sweep: interrupted", file=sys.stderr)
    sys.exit(130)

if __name__ == "__main__":
    sys.exit(main())
