// Checklist items 10-20: message channels, their FIFOs, events, sending.
using System;
using System.Collections.Generic;
using System.Threading;
using Ixxat.Vci3.Bal;
using Ixxat.Vci3.Bal.Can;
using NUnit.Framework;

namespace Canemu.Tests
{
  public class ChannelTests : DaemonFixture
  {
    // A device's BAL, control unit and a channel, opened and nothing more: the channel has no FIFOs
    // until Fifos, the line is neither initialized nor started.
    sealed class Opened : IDisposable
    {
      public readonly IBalObject Bal;
      public readonly ICanControl Control;
      public readonly ICanChannel Channel;
      public ICanMessageReader Reader;
      public ICanMessageWriter Writer;

      public Opened(string device)
      {
        Bal = T.Bal(device);
        Control = T.Open<ICanControl>(Bal);
        Channel = T.Open<ICanChannel>(Bal);
      }

      // Channel.Initialize with receive and transmit FIFOs of `rx` and `tx` messages (not
      // exclusive), and their reader and writer.
      public void Fifos(ushort rx, ushort tx)
      {
        Channel.Initialize(rx, tx, false);
        Reader = Channel.GetMessageReader();
        Writer = Channel.GetMessageWriter();
      }

      public void Dispose()
      {
        Channel.Dispose();
        Control.Dispose();
        Bal.Dispose();
      }
    }

    [Test]
    public void Item10_NoFifosUntilInitializeAndSizesCountMessages()
    {
      using (var beta = new Line("beta"))
      using (var alpha = new Opened("alpha"))
      {
        var e = T.Throws(() => alpha.Channel.GetMessageReader());
        Assert.AreEqual(0xE0010015u, e.ErrorCode);
        StringAssert.Contains("the channel has no FIFOs yet; call ICanChannel.Initialize first", e.Message);
        T.Throws(() => alpha.Channel.GetMessageWriter());
        T.Throws(() => alpha.Channel.Activate());
        e = T.Throws(() => alpha.Channel.Initialize(0, 4, false));
        StringAssert.Contains("counted in messages and must be at least 1", e.Message);
        alpha.Channel.Initialize(10, 5, false);
        var reader = alpha.Channel.GetMessageReader();
        Assert.AreEqual(10, reader.Capacity);
        Assert.AreEqual(5, alpha.Channel.GetMessageWriter().Capacity);
        alpha.Channel.Activate();
        alpha.Control.InitLine(CanOperatingModes.Standard, CanBitrate.Cia500KBit);
        alpha.Control.StartLine();
        for (byte i = 0; i < 10; i++) beta.Send(T.Msg(0x100u + i, i));
        T.Step(10);
        var got = T.Drain(reader);
        Assert.AreEqual(10, got.Count, "ten messages fit a FIFO of ten");
        for (int i = 0; i < 10; i++) Assert.AreEqual(0x100u + (uint)i, got[i].Identifier);
      }
    }

    [Test]
    public void Item11_AnExclusiveChannelIsTheOnlyOne()
    {
      using (var bal = T.Bal("alpha"))
      {
        var shared = T.Open<ICanChannel>(bal);
        var would = T.Open<ICanChannel>(bal);
        var e = T.Throws(() => would.Initialize(16, 16, true));
        Assert.AreEqual(0xE001000Au, e.ErrorCode);
        StringAssert.Contains("an exclusive channel must be the only one", e.Message);
        shared.Dispose();
        would.Initialize(16, 16, true);
        e = T.Throws(() => bal.OpenSocket(0, typeof(ICanChannel)));
        Assert.AreEqual(0xE001000Au, e.ErrorCode);
        using (var other = T.Bal("alpha")) T.Throws(() => other.OpenSocket(0, typeof(ICanChannel)));
        would.Dispose();
        T.Open<ICanChannel>(bal).Dispose();
      }
    }

    [Test]
    public void Item12_NothingFlowsUntilTheChannelIsActiveAndTheLineOnline()
    {
      using (var beta = new Line("beta"))
      using (var alpha = new Opened("alpha"))
      {
        alpha.Fifos(16, 16);
        alpha.Control.InitLine(CanOperatingModes.Standard, CanBitrate.Cia500KBit);
        alpha.Control.StartLine();
        beta.Send(T.Msg(0x1, 1));
        Assert.IsTrue(alpha.Writer.SendMessage(T.Msg(0x2, 2)), "queued in the transmit FIFO");
        T.Step(5);
        Assert.AreEqual(0, T.Drain(alpha.Reader).Count, "deactivated after open: nothing received");
        Assert.AreEqual(0, beta.Data().Count, "and nothing sent");
        alpha.Control.StopLine();
        alpha.Channel.Activate();
        beta.Send(T.Msg(0x3, 3));
        T.Step(5);
        Assert.AreEqual(0, T.Drain(alpha.Reader).Count, "active, line offline: nothing");
        Assert.AreEqual(0, beta.Data().Count);
        alpha.Control.StartLine();
        T.Step(5);
        var got = T.Drain(alpha.Reader);
        Assert.AreEqual(1, got.Count, "online: beta's pending frame");
        Assert.AreEqual(3u, got[0].Identifier);
        var sent = beta.Data();
        Assert.AreEqual(1, sent.Count, "the queued frame goes out");
        Assert.AreEqual(2u, sent[0].Identifier);
      }
    }

    [Test]
    public void Item13_EveryChannelReceivesAndTransmitFifosAreServedInTurn()
    {
      using (var beta = new Line("beta"))
      using (var alpha = new Line("alpha"))
      using (var second = T.Open<ICanChannel>(alpha.Bal))
      using (var third = T.Open<ICanChannel>(beta.Bal))
      {
        second.Initialize(16, 16, false);
        third.Initialize(16, 16, false);
        var w2 = second.GetMessageWriter();
        var r3 = third.GetMessageReader();
        third.Activate();
        alpha.Control.StopLine();
        for (byte i = 0; i < 3; i++)
        {
          alpha.Send(T.Msg(0x100u + i, i));
          Assert.IsTrue(w2.SendMessage(T.Msg(0x200u + i, i)));
        }
        second.Activate();
        alpha.Control.StartLine();
        T.Step(10);
        var order = new List<uint>();
        foreach (var m in beta.Data()) order.Add(m.Identifier);
        CollectionAssert.AreEqual(new uint[] { 0x100, 0x200, 0x101, 0x201, 0x102, 0x202 }, order,
                                  "round robin, one frame each");
        var copy = new List<uint>();
        foreach (var m in T.Drain(r3)) copy.Add(m.Identifier);
        CollectionAssert.AreEqual(order, copy, "both channels of beta got every frame");
        Assert.AreEqual(0, alpha.Data().Count, "a sibling channel does not see what the other sent");
      }
    }

    [Test]
    public void Item14_ReaderAndWriterOnceUntilDisposed()
    {
      using (var bal = T.Bal("alpha"))
      using (var channel = T.Open<ICanChannel>(bal))
      {
        channel.Initialize(8, 8, false);
        var reader = channel.GetMessageReader();
        var e = T.Throws(() => channel.GetMessageReader());
        Assert.AreEqual(0xE001000Au, e.ErrorCode);
        StringAssert.Contains("the receive FIFO's reader was obtained already; Dispose it", e.Message);
        var writer = channel.GetMessageWriter();
        e = T.Throws(() => channel.GetMessageWriter());
        StringAssert.Contains("the transmit FIFO's writer was obtained already", e.Message);
        reader.Dispose();
        writer.Dispose();
        T.Throws(() => { var x = reader.Capacity; });
        channel.GetMessageReader().Dispose();
        channel.GetMessageWriter().Dispose();
      }
    }

    [Test]
    public void Item15_ReadMessageIsFalseOnEmptyAndReadMessagesCounts()
    {
      using (var alpha = new Line("alpha"))
      using (var beta = new Line("beta"))
      {
        CanMessage m;
        Assert.IsTrue(alpha.Reader.ReadMessage(out m), "the INFO message of StartLine");
        Assert.AreEqual(CanMsgFrameType.Info, m.FrameType);
        Assert.AreEqual((byte)CanMsgInfoValue.Start, m[0]);
        Assert.IsFalse(alpha.Reader.ReadMessage(out m));
        var two = new CanMessage[2];
        Assert.AreEqual(0, alpha.Reader.ReadMessages(two));
        for (byte i = 0; i < 3; i++) beta.Send(T.Msg(0x50u + i, i));
        T.Step(5);
        var all = new List<uint>();
        int n;
        while ((n = alpha.Reader.ReadMessages(two)) > 0)
          for (int i = 0; i < n; i++) if (two[i].FrameType == CanMsgFrameType.Data) all.Add(two[i].Identifier);
        CollectionAssert.AreEqual(new uint[] { 0x50, 0x51, 0x52 }, all);
        Assert.AreEqual(0, alpha.Reader.ReadMessages(two));
      }
    }

    [Test]
    public void Item16_TheEventsFollowTheThresholds()
    {
      using (var beta = new Line("beta"))
      using (var alpha = new Opened("alpha"))
      {
        alpha.Fifos(16, 4);
        alpha.Reader.Threshold = 3;
        alpha.Writer.Threshold = 2;
        Assert.AreEqual(3, alpha.Reader.Threshold);
        var rx = new AutoResetEvent(false);
        var tx = new AutoResetEvent(false);
        alpha.Reader.AssignEvent(rx);
        alpha.Writer.AssignEvent(tx);
        alpha.Channel.Activate();
        alpha.Control.InitLine(CanOperatingModes.Standard, CanBitrate.Cia500KBit);
        Assert.IsTrue(tx.WaitOne(5000), "an empty FIFO: its free entries exceed 2");
        int queued = 0;
        while (alpha.Writer.SendMessage(T.Msg(0x10))) queued++;  // offline: they wait; until full
        Assert.GreaterOrEqual(queued, 4);
        Thread.Sleep(200);
        tx.Reset();
        Assert.IsFalse(tx.WaitOne(300), "no free entry");
        alpha.Control.StartLine();
        T.Step(5);
        Assert.IsTrue(tx.WaitOne(5000), "sent: room again");
        Assert.AreEqual(1, T.Drain(alpha.Reader, false).Count, "the INFO message of StartLine");
        Thread.Sleep(200);
        rx.Reset();
        beta.Send(T.Msg(1));
        beta.Send(T.Msg(2));
        T.Step(5);
        Assert.IsFalse(rx.WaitOne(300), "two messages: below the threshold of 3");
        beta.Send(T.Msg(3));
        T.Step(5);
        Assert.IsTrue(rx.WaitOne(5000), "the third reaches it");
        Assert.AreEqual(3, T.Drain(alpha.Reader).Count);
        Assert.IsFalse(rx.WaitOne(300));
        var e = T.Throws(() => alpha.Reader.Threshold = 4);
        StringAssert.Contains("only while the channel is deactivated", e.Message);
      }
    }

    [Test]
    public void Item17_SendMessagesReturnsHowManyWereQueued()
    {
      using (var beta = new Line("beta"))
      using (var alpha = new Line("alpha", start: false))
      {
        var batch = new CanMessage[300];
        for (int i = 0; i < batch.Length; i++) batch[i] = T.Msg((uint)i, (byte)i);
        int queued = alpha.Writer.SendMessages(batch);
        Assert.Greater(queued, 63, "at least the 64 asked for");
        Assert.Less(queued, 300, "partial: the FIFO is full");
        Assert.IsFalse(alpha.Writer.SendMessage(T.Msg(0x7FF)), "full");
        Assert.AreEqual(0, alpha.Writer.SendMessages(batch));
        alpha.Control.StartLine();
        T.Step(200);
        var got = beta.Data();
        Assert.AreEqual(queued, got.Count);
        for (int i = 0; i < queued; i++) Assert.AreEqual((uint)i, got[i].Identifier);
      }
    }

    [Test]
    public void Item18_NonDataMessagesAreDiscardedUnseen()
    {
      using (var beta = new Line("beta"))
      using (var alpha = new Line("alpha"))
      {
        var info = T.Msg(0x1, 1);
        info.FrameType = CanMsgFrameType.Info;
        var error = T.Msg(0x2, 2);
        error.FrameType = CanMsgFrameType.Error;
        Assert.AreEqual(3, alpha.Writer.SendMessages(new[] { info, error, T.Msg(0x3, 3) }));
        T.Step(5);
        var got = beta.Data();
        Assert.AreEqual(1, got.Count);
        Assert.AreEqual(3u, got[0].Identifier);
        foreach (var m in beta.All()) Assert.AreNotEqual(CanMsgFrameType.Error, m.FrameType, "no error either");
      }
    }

    [Test]
    public void Item19_RemoteFramesAreDataTypeWithRtrAndKeepTheirDlc()
    {
      using (var beta = new Line("beta"))
      using (var alpha = new Line("alpha"))
      {
        var m = new CanMessage();
        m.Identifier = 0x200;
        m.DataLength = 3;
        m.RemoteTransmissionRequest = true;
        alpha.Send(m);
        var ext = T.Msg(0x1ABCDEF0, 9);
        ext.ExtendedFrameFormat = true;
        alpha.Send(ext);
        T.Step(5);
        var got = beta.Data();
        Assert.AreEqual(2, got.Count);
        Assert.AreEqual(CanMsgFrameType.Data, got[0].FrameType);
        Assert.IsTrue(got[0].RemoteTransmissionRequest);
        Assert.AreEqual(3, got[0].DataLength);
        Assert.AreEqual(0x200u, got[0].Identifier);
        Assert.IsTrue(got[1].ExtendedFrameFormat);
        Assert.AreEqual(0x1ABCDEF0u, got[1].Identifier);
      }
    }

    [Test]
    public void Item20_DelayedTransmissionWaitsItsTicks()
    {
      using (var beta = new Line("beta"))
      using (var alpha = new Line("alpha", exclusive: true))
      {
        Assert.IsTrue(alpha.Channel.SupportsDelayedTransmission);
        Assert.AreEqual(1000000u, alpha.Channel.ClockFrequency);
        Assert.AreEqual(1u, alpha.Channel.DelayedTXTimerDivisor);
        Assert.AreEqual(65535u, alpha.Channel.MaxDelayedTXTicks);
        var first = T.Msg(0x10, 1);
        var second = T.Msg(0x10, 1);  // the same bits: the same time on the wire
        second.TimeStamp = 10000;  // 10 ms in ticks of 1 us
        var third = T.Msg(0x12, 3);  // 0: at once
        alpha.Writer.SendMessages(new[] { first, second, third });
        T.Step(5);
        var got = beta.Data();
        Assert.AreEqual(1, got.Count, "the second waits");
        T.Step(10);
        got.AddRange(beta.Data());
        Assert.AreEqual(3, got.Count);
        Assert.AreEqual(10000u, got[1].TimeStamp - got[0].TimeStamp, "handed over 10000 ticks after the first");
        Assert.Less(got[2].TimeStamp - got[1].TimeStamp, 300u, "the third without delay");
      }
    }
  }
}
