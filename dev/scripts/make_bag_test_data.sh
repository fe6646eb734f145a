#!/usr/bin/env bash
# Makes the small test bags of tests/data/bags/ from the ACES log, as ../shared/data/bags/ was made (its
# README): the log's first 10 s (lines stamped at most 80.3) as CARMEN text, then that text converted by
# ../shared/tools/clf_to_bag.py (the Python `rosbags` library, 0.11.9) into every bag format, and the same
# text without its ODOM lines (the tool then writes /odom from the FLASER lines' odometry fields).
#
#   python3 -m pip install rosbags==0.11.9 mcap==1.6.0
#   dev/scripts/make_bag_test_data.sh [SHARED_DIR]     (run from the repository's root; SHARED_DIR: ../shared)
set -euo pipefail
shared="${1:-../shared}"
tool="$shared/tools/clf_to_bag.py"
out=tests/data/bags
mkdir -p "$out"
# The stamp of a FLASER line is field 9+n, of an ODOM line field 8; other lines are kept only at stamp 0.
gzip -dc "$shared/data/logs/aces.clf.gz" | awk '{ if ($1=="FLASER") t=$(9+$2); else if ($1=="ODOM") t=$8; else t=0;
  if (t<=80.3) print }' > "$out/aces_10s.clf"
grep -v '^ODOM' "$out/aces_10s.clf" > "$out/aces_10s_no_odom.clf"
rm -rf "$out"/*.bag "$out"/*.mcap "$out"/aces_10s_mcap "$out"/aces_10s_sqlite3
python3 "$tool" "$out/aces_10s.clf" "$out/aces_10s.bag" --format ros1
python3 "$tool" "$out/aces_10s.clf" "$out/aces_10s_bz2.bag" --format ros1 --compression bz2
python3 "$tool" "$out/aces_10s.clf" "$out/aces_10s_lz4.bag" --format ros1 --compression lz4
python3 "$tool" "$out/aces_10s.clf" "$out/aces_10s_mcap" --format ros2-mcap
python3 "$tool" "$out/aces_10s.clf" "$out/aces_10s_sqlite3" --format ros2-sqlite3
python3 "$tool" "$out/aces_10s_no_odom.clf" "$out/aces_10s_no_odom.bag" --format ros1
# A bare MCAP with zstd chunks: the folder's MCAP copied record for record by the `mcap` library's writer.
python3 - "$out/aces_10s_mcap/aces_10s_mcap.mcap" "$out/aces_10s_zstd.mcap" <<'PY'
import sys
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer

with open(sys.argv[1], 'rb') as src, open(sys.argv[2], 'wb') as dst:
    reader = make_reader(src)
    writer = Writer(dst, compression=CompressionType.ZSTD)
    writer.start(profile=reader.get_header().profile, library='make_bag_test_data.sh')
    schemas, channels = {}, {}
    for schema, channel, message in reader.iter_messages(log_time_order=False):
        if schema.id not in schemas:
            schemas[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
        if channel.id not in channels:
            channels[channel.id] = writer.register_channel(channel.topic, channel.message_encoding,
                                                           schemas[schema.id], channel.metadata)
        writer.add_message(channels[channel.id], message.log_time, message.data, message.publish_time,
                           message.sequence)
    writer.finish()
PY
ls -l "$out" "$out"/aces_10s_mcap "$out"/aces_10s_sqlite3
