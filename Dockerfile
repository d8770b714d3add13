# softevo image: the package, its console script and the example robots; runs as a non-root user.
FROM python:3.11-slim

ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
    NUMBA_CACHE_DIR=/home/softevo/.cache/numba

RUN useradd --create-home --uid 10001 softevo
WORKDIR /app
COPY pyproject.toml README.md ./
COPY core ./core
COPY api ./api
COPY worker ./worker
COPY softevo ./softevo
COPY examples ./examples
RUN pip install . && chown -R softevo:softevo /app

USER softevo
CMD ["softevo", "--help"]
