from torchsym.cli import main

raise SystemExit(main())
