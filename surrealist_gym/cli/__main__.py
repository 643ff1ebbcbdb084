"""`python -m surrealist_gym.cli` = the `surrealist` command."""
import sys

from . import main

sys.exit(main())
