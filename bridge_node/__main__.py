import sys

from bridge_node.commands.cli import main

if __name__ == "__main__":
    sys.exit(main())
