"""The headless render job (``scripts/render_job.py`` is its entry point): the config read and
checked (:mod:`.config`, a crowd's tables :mod:`.crowds`), the scene built and baked
(:mod:`.build`, a job's terrain, tracks and shots :mod:`.terrain`), the files written
(:mod:`.output`), and the run from the command line to its exit status (:mod:`.job`)."""
