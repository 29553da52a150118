import sys

from bayesupdate.cli import main

sys.exit(main())
