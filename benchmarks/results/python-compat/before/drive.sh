#!/usr/bin/env bash
# Runs a sweep (ccd_sweep.py or disc_sweep.py) to its end in this folder, restarting the Python
# process after each crash, abort or hang (disc_sweep.py ends a hung query after 5 s) at the query
# after the last one it printed, which is marked " CRASH rc=<exit status>" in the log.
#   PYTHONPATH=<build>/python ./drive.sh ccd_sweep.py continuous.log
#   PYTHONPATH=<build>/python ./drive.sh disc_sweep.py discrete.log
script=$1 log=$2
start=0; : > "$log"
while true; do
  timeout 900 /usr/bin/python3 "$script" $start > part.log 2>/dev/null; rc=$?
  cat part.log >> "$log"
  if [ $rc -eq 0 ]; then break; fi
  last=$(awk 'NF>0{l=$1} END{print l}' part.log)
  echo " CRASH rc=$rc" >> "$log"
  start=$((last+1))
done
rm -f part.log
echo finished >> "$log"
