# softevo image: the package, its console script and the example robots; runs as a non-root user.
# One image for every role: `softevo serve` (default), `softevo worker`, `softevo simulate FILE`.
FROM python:3.11-slim

ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
    NUMBA_CACHE_DIR=/home/softevo/.cache/numba

RUN useradd --create-home --uid 10001 softevo
WORKDIR /app
COPY requirements/runtime.txt ./requirements/
# The locked versions first (hashes checked; a layer that stays cached while only the code changes),
# so every image, and every worker of a run, computes with the same engine.
RUN pip install -r requirements/runtime.txt
COPY pyproject.toml README.md ./
COPY core ./core
COPY api ./api
COPY worker ./worker
COPY softevo ./softevo
COPY migrations ./migrations
COPY examples ./examples
# the guides `softevo docs` shows (a package of the install: Markdown only)
COPY docs/*.md ./docs/
# Then the package itself on top of the lock, touching no dependency. The numba cache directory
# exists in the image and belongs to softevo, so a fresh named volume mounted there starts with that owner and stays writable.
RUN pip install --no-deps --no-build-isolation . \
    && mkdir -p /data "$NUMBA_CACHE_DIR" \
    && chown -R softevo:softevo /app /data /home/softevo/.cache

USER softevo
# The physics kernels compiled now, as the user that runs them, into the numba cache: a worker
# container (whose named volume on that folder starts as a copy of it) takes jobs within seconds
# of starting instead of compiling first. `-P`: /app/softevo, the source folder, must not stand
# in for the installed package. On a CPU whose features differ from the build machine's, numba
# compiles again by itself; it never computes differently.
RUN python -P -c "from softevo.core.physics.evaluation import warm_up; warm_up()" \
    && test -n "$(ls -A "$NUMBA_CACHE_DIR")"
EXPOSE 8000
CMD ["softevo", "serve", "--host", "0.0.0.0", "--port", "8000"]
