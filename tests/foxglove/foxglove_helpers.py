"""Reading MCAP files back in tests, with the `mcap` library alone."""
from __future__ import annotations

import json
from collections import defaultdict


def read_mcap(path):
    """(summary, {topic: [(log_time ns, schema name, decoded message)]}) of an MCAP file,
    decoded with the `mcap` library alone (protobuf for Foxglove's schemas, JSON for ours)."""
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    factory, decoders = DecoderFactory(), {}
    messages = defaultdict(list)
    with open(path, "rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        for schema, channel, message in reader.iter_messages():
            if schema.encoding == "protobuf":
                if channel.id not in decoders:
                    decoders[channel.id] = factory.decoder_for(channel.message_encoding, schema)
                decoded = decoders[channel.id](message.data)
            else:
                assert schema.encoding == "jsonschema" and channel.message_encoding == "json"
                decoded = json.loads(message.data)
            messages[channel.topic].append((message.log_time, schema.name, decoded))
    return summary, messages
