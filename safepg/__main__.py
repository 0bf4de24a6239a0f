from safepg.cli import main

raise SystemExit(main())
