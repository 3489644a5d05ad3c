#!/usr/bin/env bash
# Session 52, call 3: call1.sh again, after the bench gained its small meshes and the library its
# KDET_FCL_INTERPOSE_CACHE setting, with the trust cache's bench run as well.
TRUST_RUN=1 NAME=call3 exec bash "$(dirname "$0")/call1.sh"
