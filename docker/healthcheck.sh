#!/bin/bash
# The image's HEALTHCHECK: GET /api/health on the server's own port (PEAKCAST_PORT), with bash's
# /dev/tcp so that the image needs no HTTP client. Exit 0 when the server answers 200.
exec 3<>"/dev/tcp/127.0.0.1/${PEAKCAST_PORT:-8080}" || exit 1
printf 'GET /api/health HTTP/1.0\r\nHost: localhost\r\n\r\n' >&3
IFS= read -r -t 5 status <&3 || exit 1
[[ $status == "HTTP/1."[01]" 200"* ]]
