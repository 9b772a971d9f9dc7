import sys

from pymunk_bot.cli.entry import main

sys.exit(main())
